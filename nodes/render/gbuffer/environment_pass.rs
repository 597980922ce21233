//! `environment_pass`: the environment behind the surfaces, Framework3D's
//! `render_environment_pass` with the course's `environment_map.fs`: where the depth pass
//! says nothing was hit, the colour is the environment seen along the pixel's camera ray;
//! elsewhere it is the input colour (the course shader adds no ambient term). The
//! environment is the scene's first `Light::Environment` (Framework3D's dome light),
//! looked up with the tracers' equirectangular mapping and rotation
//! (`nodes/trace/environment.rs`: +y up, the image centre towards -z) where the course's
//! shader uses a cylindrical map around +z. Without an environment light the `background`
//! colour fills in, and the node logs a warning.

use super::{camera_ray, check_size, depth_hit, pass_camera, rgb1, Sky};
use cgnodes_api::prelude::*;

/// `color` where `depth` holds a surface, else the sky along the camera ray of `cam`
/// (whose resolution is the images'). Output alpha is 1.
pub fn environment_pass(color: &Image, depth: &Image, cam: &Camera, sky: &Sky) -> Image {
    let look = cam.look_at::<f64>();
    let f = cam.focal_length_px();
    let (w, h) = (depth.width, depth.height);
    super::image_from_fn(w, h, |x, y| {
        if depth_hit(depth.get(x, y)) {
            let c = color.get(x, y);
            [c[0], c[1], c[2], 1.0]
        } else {
            rgb1(sky.eval(camera_ray(&look, f, w, h, x, y)))
        }
    })
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Fills pixels where nothing was hit with the scene's environment light seen along the camera ray (Framework3D's render_environment_pass).");
    b.add_input::<Scene>("scene")
        .doc("Its first environment light is the sky (and its camera is used when 'camera' is not connected).");
    b.add_input::<Camera>("camera")
        .optional()
        .doc("The camera the G-buffer was rendered with.");
    b.add_input::<Image>("color")
        .doc("Colour where a surface was hit.");
    b.add_input::<Image>("depth")
        .doc("Depth pass: 0 or alpha 0 where nothing was hit.");
    b.add_input::<Color>("background")
        .default(Color([0.0, 0.0, 0.0]))
        .doc("Sky colour when the scene has no environment light (a warning is logged).");
    b.add_output::<Image>("color")
        .doc("Colour with the environment behind.");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let scene: Arc<Scene> = ctx.input("scene")?;
    let color: Arc<Image> = ctx.input("color")?;
    let depth: Arc<Image> = ctx.input("depth")?;
    let (w, h) = (depth.width, depth.height);
    check_size("depth", &depth, w, h)?;
    check_size("color", &color, w, h)?;
    let cam = pass_camera(ctx.input_opt("camera")?, Some(&scene), w, h)?;
    let bg: Color = ctx.input("background")?;
    let sky = Sky::new(&scene.lights, bg.0);
    if !sky.has_environment() {
        ctx.log("warning: the scene has no environment light; the background colour fills the empty pixels");
    }
    ctx.set_output("color", environment_pass(&color, &depth, &cam, &sky));
    Ok(())
}

/// Registers `environment_pass`.
pub fn register(r: &mut Registry) {
    r.add("environment_pass", declare, execute);
}
