//! `camera`: a look-at pinhole camera (eye, target, up; field of view; resolution; clip range).
//!
//! The camera geometry shared by the rasterizer and the tracers (look-at frame, field of
//! view, focal length, validation) is in methods of `Camera` (`src/types/scene.rs`).

use cgnodes_api::prelude::*;

fn declare(b: &mut NodeBuilder) {
    b.doc("A look-at pinhole camera.");
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
    b.add_choice::<FovAxis>("fov_axis")
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
    let fov_axis = ctx.choice::<FovAxis>("fov_axis")?;
    let w: i64 = ctx.input("width")?;
    let h: i64 = ctx.input("height")?;
    // width and height lie in their declared ranges (checked by the runtime).
    let cam = Camera {
        eye: ctx.input("eye")?,
        target: ctx.input("target")?,
        up: ctx.input("up")?,
        fov_deg: ctx.input("fov")?,
        fov_axis,
        width: w as u32,
        height: h as u32,
        near: ctx.input("near")?,
        far: ctx.input("far")?,
    };
    cam.check().map_err(|e| NodeError::invalid("eye", e))?;
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
        match &super::super::run_node("camera", inputs)?["camera"] {
            Value::Camera(c) => Ok((**c).clone()),
            _ => panic!("not a camera"),
        }
    }

    #[test]
    fn defaults_and_frame() {
        let cam = run(BTreeMap::new()).unwrap();
        assert_eq!(cam, Camera::default());
        let [r, u, f] = cam.frame().unwrap();
        assert_eq!(r, [1.0, 0.0, 0.0]);
        assert_eq!(u, [0.0, 1.0, 0.0]);
        assert_eq!(f, [0.0, 0.0, -1.0]);
        // 45 degrees over 512 pixels: tan(22.5 deg) * fy = 256.
        let fx = cam.focal_length_px();
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
        let fx = cam.focal_length_px();
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
