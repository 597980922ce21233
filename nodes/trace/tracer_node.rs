//! What the tracer nodes (`render_path`, `render_whitted`) share around the renderers:
//! the image-size check and the mapping of a renderer's error to the socket it concerns.

use super::render_scene::TraceError;
use cgnodes_api::prelude::*;

/// Checks that a tracer's image buffers, `bytes_per_pixel` for every pixel of the camera's
/// image (the linked `camera`, else the scene's), fit under the run's memory limit before
/// rendering; an error on `camera` stating the size otherwise. Without any camera it passes
/// (the renderer reports the missing camera).
pub fn reserve_image(
    ctx: &ExecContext,
    scene: &Scene,
    camera: Option<&Camera>,
    bytes_per_pixel: u64,
) -> Result<(), NodeError> {
    let Some(c) = camera.or(scene.camera.as_ref()) else {
        return Ok(());
    };
    let bytes = cgnodes_api::node::bytes_of(&[c.width as u64, c.height as u64, bytes_per_pixel]);
    ctx.reserve_bytes(
        "camera",
        &format!("a {}x{} image", c.width, c.height),
        bytes,
    )
}

/// A renderer's error as a node error on the socket it concerns.
pub fn trace_error(e: TraceError) -> NodeError {
    NodeError::invalid(e.socket(), e.to_string())
}

/// Declares the `crease_angle` input both tracers take.
pub fn declare_crease(b: &mut NodeBuilder) {
    b.add_input::<f64>("crease_angle")
        .default(super::render_scene::DEFAULT_CREASE_DEG)
        .range(0.0, 180.0)
        .doc("For meshes without normals: smooth shading across edges whose faces differ by less than this angle in degrees (0 = flat, 180 = all smooth). Normals from the file are used as they are.");
}

/// Reads and checks `crease_angle`.
pub fn crease_input(ctx: &ExecContext) -> Result<f64, NodeError> {
    let c: f64 = ctx.input("crease_angle")?;
    if !(0.0..=180.0).contains(&c) {
        return Err(NodeError::invalid(
            "crease_angle",
            format!("{c} must be in 0..=180 degrees"),
        ));
    }
    Ok(c)
}
