//! `light_point`, `light_directional` and `light_environment`: the scene's light sources.
//!
//! A point light radiates `color * intensity` (W/sr per channel) in every direction, so the
//! irradiance it gives a surface at distance d facing it is `color * intensity / d^2`; a
//! directional light gives irradiance `color * intensity` on a surface facing it. An
//! environment light (tracers only) is radiance arriving from infinitely far in every
//! direction, from an equirectangular image or a constant colour.

use cgnodes_api::prelude::*;

/// Why a point or directional light's values are refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LightError {
    /// A position, direction, colour or intensity component is NaN or infinite.
    #[error("values must be finite")]
    NotFinite,
    /// A colour component or the intensity is below zero.
    #[error("color and intensity must not be negative")]
    Negative,
    /// A directional light's direction has no length.
    #[error("direction must not be zero")]
    ZeroDirection,
}

/// A point light; fails on non-finite or negative values.
pub fn point_light(
    position: [f64; 3],
    color: [f64; 3],
    intensity: f64,
) -> Result<Light, LightError> {
    check(&position, &color, intensity)?;
    Ok(Light::Point {
        position,
        color,
        intensity,
    })
}

/// A directional light travelling along `direction` (normalized here); fails on a zero
/// direction or non-finite or negative values.
pub fn directional_light(
    direction: [f64; 3],
    color: [f64; 3],
    intensity: f64,
) -> Result<Light, LightError> {
    check(&direction, &color, intensity)?;
    let n = cgnodes_api::types::vec3::norm(direction);
    if n.is_nan() || n <= 1e-12 {
        return Err(LightError::ZeroDirection);
    }
    Ok(Light::Directional {
        direction: cgnodes_api::types::vec3::scale(direction, 1.0 / n),
        color,
        intensity,
    })
}

/// The checks both lights share: finite values, non-negative colour and intensity.
fn check(p: &[f64; 3], color: &[f64; 3], intensity: f64) -> Result<(), LightError> {
    if p.iter().chain(color).any(|x| !x.is_finite()) || !intensity.is_finite() {
        return Err(LightError::NotFinite);
    }
    if color.iter().any(|&c| c < 0.0) || intensity < 0.0 {
        return Err(LightError::Negative);
    }
    Ok(())
}

/// The sockets both lights have, in order: the vector placing the light (`name`, default,
/// doc), colour, intensity (default, doc), and the `light` output.
fn declare_light(
    b: &mut NodeBuilder,
    doc: &str,
    vector: (&str, [f64; 3], &str),
    intensity: (f64, &str),
) {
    b.doc(doc);
    b.add_input::<[f64; 3]>(vector.0)
        .default(vector.1)
        .doc(vector.2);
    b.add_input::<Color>("color")
        .default(Color([1.0, 1.0, 1.0]))
        .doc("Linear RGB colour.");
    b.add_input::<f64>("intensity")
        .default(intensity.0)
        .min(0.0)
        .doc(intensity.1);
    b.add_output::<Light>("light");
}

fn declare_point(b: &mut NodeBuilder) {
    declare_light(
        b,
        "A point light radiating color * intensity (W/sr) in every direction.",
        ("position", [2.0, 4.0, 3.0], "Light position."),
        (
            10.0,
            "Radiant intensity (irradiance at distance d is intensity / d^2).",
        ),
    );
}

fn execute_point(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let c: Color = ctx.input("color")?;
    let l = point_light(ctx.input("position")?, c.0, ctx.input("intensity")?)
        .map_err(|e| NodeError::invalid("intensity", e.to_string()))?;
    ctx.set_output("light", l);
    Ok(())
}

fn declare_directional(b: &mut NodeBuilder) {
    declare_light(
        b,
        "A distant light travelling along a direction, with irradiance color * intensity.",
        (
            "direction",
            [-1.0, -2.0, -1.0],
            "Direction the light travels (from the light towards the scene).",
        ),
        (1.0, "Irradiance on a surface facing the light."),
    );
}

fn execute_directional(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let c: Color = ctx.input("color")?;
    let l = directional_light(ctx.input("direction")?, c.0, ctx.input("intensity")?)
        .map_err(|e| NodeError::invalid("direction", e.to_string()))?;
    ctx.set_output("light", l);
    Ok(())
}

/// An environment light; fails on non-finite or negative values (in the image too) or a
/// non-finite rotation. Errors name the socket.
pub fn environment_light(
    image: Option<Arc<Image>>,
    color: [f64; 3],
    intensity: f64,
    rotation_deg: f64,
) -> Result<Light, NodeError> {
    check(&[0.0; 3], &color, intensity)
        .map_err(|e| NodeError::invalid("intensity", e.to_string()))?;
    if !rotation_deg.is_finite() {
        return Err(NodeError::invalid("rotation", "rotation must be finite"));
    }
    if let Some(img) = &image {
        if img.width == 0
            || img.height == 0
            || img.pixels.len() != (img.width * img.height) as usize
        {
            return Err(NodeError::invalid("image", "the image is empty"));
        }
        if let Some(i) = img
            .pixels
            .iter()
            .position(|p| p[..3].iter().any(|c| !c.is_finite() || *c < 0.0))
        {
            return Err(NodeError::invalid(
                "image",
                format!(
                    "pixel ({}, {}) is negative or not finite; radiance must be finite and >= 0",
                    i as u32 % img.width,
                    i as u32 / img.width
                ),
            ));
        }
    }
    Ok(Light::Environment {
        image,
        color,
        intensity,
        rotation_deg,
    })
}

fn declare_environment(b: &mut NodeBuilder) {
    b.doc("Light from every direction for the tracers: an equirectangular radiance image (HDR/EXR) times color * intensity, or a constant sky.");
    b.add_input::<Image>("image").optional().doc(
        "Equirectangular radiance (linear; load EXR/HDR with color_space = raw): row 0 looks straight up (+y), the image centre along -z, u grows towards +x. Without it the sky is the constant colour.",
    );
    b.add_input::<Color>("color")
        .default(Color([1.0, 1.0, 1.0]))
        .doc("Linear RGB radiance (multiplies the image).");
    b.add_input::<f64>("intensity")
        .default(1.0)
        .min(0.0)
        .doc("Scale of the radiance.");
    b.add_input::<f64>("rotation")
        .default(0.0)
        .doc("Turns the environment about +y, in degrees (counter-clockwise seen from above).");
    b.add_output::<Light>("light");
}

fn execute_environment(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let c: Color = ctx.input("color")?;
    let l = environment_light(
        ctx.input_opt("image")?,
        c.0,
        ctx.input("intensity")?,
        ctx.input("rotation")?,
    )?;
    ctx.set_output("light", l);
    Ok(())
}

/// Registers `light_point`, `light_directional` and `light_environment`.
pub fn register(r: &mut Registry) {
    r.add(
        "light_environment",
        declare_environment,
        execute_environment,
    );
    r.add("light_point", declare_point, execute_point);
    r.add(
        "light_directional",
        declare_directional,
        execute_directional,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn run(name: &str, inputs: BTreeMap<String, Value>) -> Result<Light, NodeError> {
        match &super::super::run_node(name, inputs)?["light"] {
            Value::Light(l) => Ok((**l).clone()),
            _ => panic!("not a light"),
        }
    }

    #[test]
    fn point_light_takes_its_inputs() {
        let mut inp = BTreeMap::new();
        inp.insert("position".into(), Value::Vec3([1.0, 2.0, 3.0]));
        inp.insert("color".into(), Value::Color([0.5, 0.25, 1.0]));
        inp.insert("intensity".into(), Value::Float(7.0));
        assert_eq!(
            run("light_point", inp).unwrap(),
            Light::Point {
                position: [1.0, 2.0, 3.0],
                color: [0.5, 0.25, 1.0],
                intensity: 7.0
            }
        );
    }

    #[test]
    fn directional_light_is_normalized_and_checked() {
        let mut inp = BTreeMap::new();
        inp.insert("direction".into(), Value::Vec3([0.0, -3.0, 4.0]));
        match run("light_directional", inp).unwrap() {
            Light::Directional { direction, .. } => {
                assert!((direction[1] + 0.6).abs() < 1e-12 && (direction[2] - 0.8).abs() < 1e-12)
            }
            _ => panic!(),
        }
        let mut inp = BTreeMap::new();
        inp.insert("direction".into(), Value::Vec3([0.0; 3]));
        assert!(run("light_directional", inp).is_err());
        let mut inp = BTreeMap::new();
        inp.insert("intensity".into(), Value::Float(-1.0));
        assert!(run("light_point", inp).is_err());
    }

    #[test]
    fn environment_light_checks_its_image() {
        let l = run("light_environment", BTreeMap::new()).unwrap();
        assert!(matches!(l, Light::Environment { image: None, intensity, .. } if intensity == 1.0));
        let mut img = Image::new(4, 2, [1.0; 4]);
        img.set(3, 1, [0.5, -1.0, 0.0, 1.0]);
        let mut inp = BTreeMap::new();
        inp.insert("image".into(), Value::from(img));
        let e = run("light_environment", inp).unwrap_err();
        assert!(e.to_string().contains("(3, 1)"), "{e}");
        let mut inp = BTreeMap::new();
        inp.insert("rotation".into(), Value::Float(f64::NAN));
        assert!(run("light_environment", inp).is_err());
    }
}
