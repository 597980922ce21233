//! `camera`: a look-at pinhole camera (eye, target, up; field of view; resolution; clip range).
//!
//! Also holds the camera geometry shared by the rasterizer and the tracers: the orthonormal
//! look-at frame and the focal lengths in pixels.

use crate::prelude::*;

/// The camera's orthonormal frame `(right, up, forward)`, right-handed world: `forward`
/// points from the eye to the target, `right = forward x up`, `up = right x forward`
/// (the `gluLookAt` convention). Fails when eye = target or `up` is parallel to the view.
pub fn camera_frame(cam: &Camera) -> Result<[[f64; 3]; 3], String> {
    let f = sub(cam.target, cam.eye);
    let fl = norm(f);
    if fl.is_nan() || fl <= 1e-12 {
        return Err("eye and target coincide".into());
    }
    let f = scale(f, 1.0 / fl);
    let r = cross(f, cam.up);
    let rl = norm(r);
    if rl.is_nan() || rl <= 1e-9 * norm(cam.up).max(1e-300) || !rl.is_finite() {
        return Err("up is parallel to the viewing direction (or zero)".into());
    }
    let r = scale(r, 1.0 / rl);
    let u = cross(r, f);
    Ok([r, u, f])
}

/// Focal lengths `(fx, fy)` in pixels: a camera-space point `(x, y, z)` (x right, y up,
/// z forward) lands at pixel `(w/2 + fx x/z, h/2 - fy y/z)` (square pixels, so fx = fy).
pub fn focal_lengths(cam: &Camera) -> (f64, f64) {
    let fy = 0.5 * cam.height as f64 / (0.5 * cam.vertical_fov()).tan();
    (fy, fy)
}

/// Checks that a camera describes a usable projection.
pub fn check_camera(cam: &Camera) -> Result<(), String> {
    camera_frame(cam)?;
    if !(cam.fov_deg > 0.0 && cam.fov_deg < 180.0) {
        return Err(format!("fov {} must lie in (0, 180) degrees", cam.fov_deg));
    }
    if cam.width == 0 || cam.height == 0 || cam.width > 16384 || cam.height > 16384 {
        return Err(format!(
            "resolution {}x{} must lie in 1..=16384",
            cam.width, cam.height
        ));
    }
    if !(cam.near > 0.0 && cam.far > cam.near && cam.far.is_finite()) {
        return Err(format!(
            "need 0 < near < far, got near {} far {}",
            cam.near, cam.far
        ));
    }
    Ok(())
}

pub(crate) use crate::types::vec3::{cross, norm, scale, sub};

fn declare(b: &mut NodeBuilder) {
    b.doc("A look-at pinhole camera.").category("render");
    b.add_input::<[f64; 3]>("eye")
        .default([0.0, 0.0, 3.0])
        .doc("Camera position.");
    b.add_input::<[f64; 3]>("target")
        .default([0.0, 0.0, 0.0])
        .doc("Point looked at.");
    b.add_input::<[f64; 3]>("up")
        .default([0.0, 1.0, 0.0])
        .doc("Up direction.");
    b.add_input::<f64>("fov")
        .default(45.0)
        .range(0.001, 179.9)
        .doc("Field of view in degrees along fov_axis.");
    b.add_input::<String>("fov_axis")
        .choices(&["vertical", "smaller"])
        .doc("Image axis the field of view spans.");
    b.add_input::<i64>("width")
        .default(512i64)
        .range(1.0, 16384.0)
        .doc("Image width in pixels.");
    b.add_input::<i64>("height")
        .default(512i64)
        .range(1.0, 16384.0)
        .doc("Image height in pixels.");
    b.add_input::<f64>("near")
        .default(0.01)
        .min(1e-9)
        .doc("Near clipping distance.");
    b.add_input::<f64>("far")
        .default(1000.0)
        .doc("Far clipping distance.");
    b.add_output::<Camera>("camera");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let axis: String = ctx.input("fov_axis")?;
    let w: i64 = ctx.input("width")?;
    let h: i64 = ctx.input("height")?;
    if !(1..=16384).contains(&w) {
        return Err(NodeError::invalid("width", "must lie in 1..=16384"));
    }
    if !(1..=16384).contains(&h) {
        return Err(NodeError::invalid("height", "must lie in 1..=16384"));
    }
    let cam = Camera {
        eye: ctx.input("eye")?,
        target: ctx.input("target")?,
        up: ctx.input("up")?,
        fov_deg: ctx.input("fov")?,
        fov_axis: if axis == "smaller" {
            FovAxis::Smaller
        } else {
            FovAxis::Vertical
        },
        width: w as u32,
        height: h as u32,
        near: ctx.input("near")?,
        far: ctx.input("far")?,
    };
    check_camera(&cam).map_err(|e| NodeError::invalid("eye", e))?;
    ctx.set_output("camera", cam);
    Ok(())
}

/// Registers `camera`.
pub fn register(r: &mut Registry) {
    r.add("camera", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn run(inputs: BTreeMap<String, Value>) -> Result<Camera, NodeError> {
        let mut r = Registry::new();
        register(&mut r);
        let decl = r.get("camera").unwrap();
        let mut state = None;
        let files = FileEnv::default();
        let mut ctx = ExecContext::standalone(decl, inputs, &mut state, &files, 0);
        (decl.exec.as_ref().unwrap())(&mut ctx)?;
        let outs = ctx.take_outputs();
        match &outs["camera"] {
            Value::Camera(c) => Ok((**c).clone()),
            _ => panic!("not a camera"),
        }
    }

    #[test]
    fn defaults_and_frame() {
        let cam = run(BTreeMap::new()).unwrap();
        assert_eq!(cam, Camera::default());
        let [r, u, f] = camera_frame(&cam).unwrap();
        assert_eq!(r, [1.0, 0.0, 0.0]);
        assert_eq!(u, [0.0, 1.0, 0.0]);
        assert_eq!(f, [0.0, 0.0, -1.0]);
        // 45 degrees over 512 pixels: tan(22.5 deg) * fy = 256.
        let (fx, _) = focal_lengths(&cam);
        assert!((fx * (22.5f64).to_radians().tan() - 256.0).abs() < 1e-9);
    }

    #[test]
    fn smaller_axis_on_portrait_image() {
        let mut inp = BTreeMap::new();
        inp.insert("fov_axis".into(), Value::from("smaller"));
        inp.insert("width".into(), Value::Int(200));
        inp.insert("height".into(), Value::Int(400));
        inp.insert("fov".into(), Value::Float(90.0));
        let cam = run(inp).unwrap();
        // Horizontal half-width at unit distance is tan(45 deg) = 1 over 100 pixels.
        let (fx, _) = focal_lengths(&cam);
        assert!((fx - 100.0).abs() < 1e-9);
    }

    #[test]
    fn degenerate_cameras_are_errors() {
        let mut inp = BTreeMap::new();
        inp.insert("eye".into(), Value::Vec3([0.0, 0.0, 0.0]));
        assert!(run(inp).is_err());
        let mut inp = BTreeMap::new();
        inp.insert("up".into(), Value::Vec3([0.0, 0.0, 1.0]));
        assert!(run(inp).is_err());
        let mut inp = BTreeMap::new();
        inp.insert("near".into(), Value::Float(10.0));
        inp.insert("far".into(), Value::Float(1.0));
        assert!(run(inp).is_err());
    }
}
