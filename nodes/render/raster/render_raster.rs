//! `render_raster`: the node wrapping the rasterizer (`super::render`): reads the settings,
//! renders only the passes someone reads, and sets them as outputs.

use super::options::{AntiAliasing, Passes, RasterOptions};
use super::shadow::ShadowParams;
use super::texture::Wrap;
use super::{raster_bytes, render_progress};
use cgnodes_api::prelude::*;

impl Choice for AntiAliasing {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("msaa", AntiAliasing::Multisampling),
        ("ssaa", AntiAliasing::Supersampling),
    ];
}

/// The shadow lookup's sockets (`pcf_radius`, `shadow_bias`, `shadow_slope_bias`), shared by
/// `render_raster` and the G-buffer's `deferred_lighting`.
pub(crate) fn declare_shadow_params(b: &mut NodeBuilder) {
    let d = ShadowParams::default();
    b.add_input::<i64>("pcf_radius")
        .default(d.pcf_radius as i64)
        .range(0.0, 4.0)
        .doc("Percentage-closer filtering radius r: (2r+1)^2 taps.");
    b.add_input::<f64>("shadow_bias")
        .default(d.bias)
        .range(0.0, 100.0)
        .doc("Constant depth bias, in shadow-map texels.");
    b.add_input::<f64>("shadow_slope_bias")
        .default(d.slope_bias)
        .range(0.0, 100.0)
        .doc("Slope-scaled depth bias, in texels per unit tan(angle) and PCF ring.");
}

/// Reads the sockets of `declare_shadow_params` (their ranges, NaN refused, are checked by
/// the runtime before the node runs).
pub(crate) fn read_shadow_params(ctx: &mut ExecContext) -> Result<ShadowParams, NodeError> {
    let pcf: i64 = ctx.input("pcf_radius")?;
    Ok(ShadowParams {
        pcf_radius: pcf as u32,
        bias: ctx.input("shadow_bias")?,
        slope_bias: ctx.input("shadow_slope_bias")?,
    })
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Rasterizes a scene: Blinn-Phong with shadow maps, textures and normal maps, plus deferred passes.");
    b.add_input::<Scene>("scene")
        .doc("Meshes, materials, lights and usually the camera.");
    b.add_input::<Camera>("camera")
        .optional()
        .doc("Camera; overrides the scene's camera.");
    b.add_choice::<AntiAliasing>("antialiasing")
        .doc("msaa shades each triangle once per pixel; ssaa shades every sample.");
    let d = RasterOptions::default();
    b.add_input::<i64>("samples")
        .default((d.samples_per_axis * d.samples_per_axis) as i64)
        .range(1.0, 64.0)
        .doc("Samples per pixel: a square, 1, 4, 9, 16, ...");
    b.add_input::<bool>("cull_backfaces")
        .default(d.cull_backfaces)
        .doc("Skip triangles seen from behind (clockwise on screen).");
    b.add_input::<bool>("shadows")
        .default(d.shadows)
        .doc("Render shadow maps.");
    b.add_input::<i64>("shadow_resolution")
        .default(d.shadow_resolution as i64)
        .range(256.0, 8192.0)
        .doc("Shadow map size; point-light cube faces use half of it.");
    declare_shadow_params(b);
    b.add_input::<f64>("ambient")
        .default(d.ambient)
        .range(0.0, 10.0)
        .doc("Ambient term ka*Ia, times the base colour.");
    b.add_choice::<Wrap>("texture_wrap")
        .doc("What textures do outside UV 0..1.");
    b.add_input::<bool>("mipmaps")
        .default(d.mipmaps)
        .doc("Trilinear filtering through a mipmap pyramid (else bilinear).");
    b.add_input::<Color>("background")
        .default(Color(d.background))
        .doc("Colour where nothing is hit.");
    b.add_output::<Image>("color").doc("Shaded linear colour.");
    b.add_output::<Image>("depth")
        .doc("View depth along the viewing direction.");
    b.add_output::<Image>("normal")
        .doc("World-space shading normal.");
    b.add_output::<Image>("position")
        .doc("World-space position.");
    b.add_output::<Image>("uv")
        .doc("Texture coordinates (R, G).");
    b.add_output::<Image>("base_color")
        .doc("Base colour (texture times factor).");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let scene: Arc<Scene> = ctx.input("scene")?;
    let cam: Option<Arc<Camera>> = ctx.input_opt("camera")?;
    let cam = match (cam, &scene.camera) {
        (Some(c), _) => (*c).clone(),
        (None, Some(c)) => c.clone(),
        (None, None) => {
            return Err(NodeError::invalid(
                "camera",
                "the scene has no camera; connect one to 'camera' or to the scene node",
            ))
        }
    };
    let samples: i64 = ctx.input("samples")?;
    let sa = (samples.max(1) as f64).sqrt().round() as i64;
    if sa * sa != samples || !(1..=8).contains(&sa) {
        return Err(NodeError::invalid(
            "samples",
            format!("{samples} is not a square number of samples in 1..=64"),
        ));
    }
    let aa = ctx.choice::<AntiAliasing>("antialiasing")?;
    // Ranges (NaN refused) are checked by the runtime from the declaration.
    let res: i64 = ctx.input("shadow_resolution")?;
    let shadow = read_shadow_params(ctx)?;
    let ambient: f64 = ctx.input("ambient")?;
    let wrap = ctx.choice::<Wrap>("texture_wrap")?;
    let bgc: Color = ctx.input("background")?;
    let opts = RasterOptions {
        samples_per_axis: sa as u32,
        aa,
        cull_backfaces: ctx.input("cull_backfaces")?,
        shadows: ctx.input("shadows")?,
        shadow_resolution: res as u32,
        shadow,
        ambient,
        wrap,
        mipmaps: ctx.input("mipmaps")?,
        background: bgc.0,
        // Only the passes someone reads are computed (and allocated).
        passes: Passes {
            color: ctx.output_wanted("color"),
            depth: ctx.output_wanted("depth"),
            normal: ctx.output_wanted("normal"),
            position: ctx.output_wanted("position"),
            uv: ctx.output_wanted("uv"),
            base_color: ctx.output_wanted("base_color"),
        },
    };
    let what = format!(
        "a {}x{} image with {} samples per pixel",
        cam.width, cam.height, samples
    );
    ctx.reserve_bytes(
        "camera",
        &what,
        raster_bytes(&cam, &opts, scene.lights.len()),
    )?;
    let out = render_progress(&scene, &cam, &opts, &ctx.progress_fn())
        .map_err(|e| NodeError::invalid("scene", e.to_string()))?;
    ctx.log(format!(
        "{}x{} with {} samples: {} triangles, {} shading evaluations",
        cam.width, cam.height, samples, out.triangles, out.shaded
    ));
    for (name, on, img) in [
        ("color", opts.passes.color, out.color),
        ("depth", opts.passes.depth, out.depth),
        ("normal", opts.passes.normal, out.normal),
        ("position", opts.passes.position, out.position),
        ("uv", opts.passes.uv, out.uv),
        ("base_color", opts.passes.base_color, out.base_color),
    ] {
        if on {
            ctx.set_output(name, img);
        }
    }
    Ok(())
}

/// Registers `render_raster`.
pub fn register(r: &mut Registry) {
    r.add("render_raster", declare, execute);
}
