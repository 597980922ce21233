//! `render_raster`: a CPU rasterizer producing a shaded image and the deferred passes
//! (depth, normal, position, uv, base colour), as Framework3D's rasterize node gives them.
//!
//! Pipeline: the scene is flattened to world-space triangles (`geometry`). Two independent
//! stages then run side by side: `setup` transforms each triangle with the camera's view
//! and projection (methods of `Camera`), clips it and sets it up in 2D homogeneous
//! coordinates (`rasterize`), binned into bands; `lights` prepares each light and renders
//! its shadow map (`shadow`). `resolve` rasterizes each band into a visibility buffer
//! holding the nearest depth and triangle per sample (tiled in bands, rayon-parallel,
//! deterministic) and shades it right away through `shader`: attributes are reconstructed
//! with perspective-correct barycentrics at the sample position, textures are filtered
//! trilinearly with UV derivatives taken one pixel over (`texture`), normal maps perturb
//! the normal in the tangent frame, and each light adds Blinn-Phong (`shading`) times its
//! shadow-map visibility. Settings and results are in `options`; the node is in
//! `render_raster`.
//!
//! Anti-aliasing with `n = s^2` samples per pixel on an `s x s` grid: `ssaa` shades every
//! sample; `msaa` shades each triangle once per pixel, at the centroid of the samples it
//! covers, weighted by its coverage (the visibility-buffer form of multisampling). The
//! passes come from the nearest triangle in the pixel, evaluated at the centroid of its
//! samples; their alpha is 1 where a surface was hit and 0 elsewhere. Colour is linear
//! with alpha 1 (the background colour shows where nothing was hit).

pub use cgnodes_geometry::scene_geometry as geometry;
mod lights;
pub mod options;
pub mod rasterize;
pub mod render_raster;
mod resolve;
mod scratch;
mod setup;
mod shader;
pub mod shading;
pub mod shadow;
pub use cgnodes_geometry::texture;

use cgnodes_api::prelude::*;
pub use lights::light_at;
pub use options::{AntiAliasing, Passes, RasterOptions, RenderOutput};
use rayon::prelude::*;
pub use scratch::release_scratch;

/// Why the rasterizer cannot render a scene.
#[derive(Debug, thiserror::Error)]
pub enum RasterError {
    /// The camera is unusable (degenerate frame, field of view or clipping planes).
    #[error("{0}")]
    Camera(crate::BoxedError),
    /// The scene cannot be flattened to triangles (non-finite geometry).
    #[error("{0}")]
    Geometry(crate::BoxedError),
}

/// Renders a scene through a camera (see the module doc). Fails on an unusable camera or
/// non-finite geometry. Only the passes in `opts.passes` are produced.
pub fn render(
    scene: &Scene,
    cam: &Camera,
    opts: &RasterOptions,
) -> Result<RenderOutput, RasterError> {
    render_progress(scene, cam, opts, &|_| {})
}

/// `render`, reporting the fraction of image bands resolved (for progress bars).
pub fn render_progress(
    scene: &Scene,
    cam: &Camera,
    opts: &RasterOptions,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<RenderOutput, RasterError> {
    cam.check().map_err(|e| RasterError::Camera(e.into()))?;
    let s = opts.samples_per_axis.clamp(1, 8);
    let lit = opts.passes.color;
    let g = geometry::scene_geometry_in(scene, 180.0, scratch::take_geometry())
        .map_err(|e| RasterError::Geometry(e.into()))?;
    let band_rows = resolve::BAND_PX as u32 * s;
    // The camera's triangle setup and the shadow maps (one light per task) are
    // independent: build them side by side.
    let ((setups, ngs, bins), mut lights) = rayon::join(
        || setup::camera_setup(&g, cam, s, band_rows, opts.cull_backfaces),
        || lights::prepare_lights(scene, &g, opts, lit),
    );
    // A directional light's shadow-bias factor depends on the triangle only: once per
    // triangle here instead of once per lookup.
    for lp in &mut lights {
        if let (Some((l, _)), Some(_)) = (lp.dir, &lp.map) {
            let mut f = scratch::FACTORS.take(ngs.len());
            ngs.par_iter()
                .map(|ng| ng.map_or(0.0, |ng| shadow::bias_factor(ng, l, &opts.shadow)))
                .collect_into_vec(&mut f);
            lp.factors = f;
        }
    }
    let triangles = setups.iter().filter(|t| t.is_some()).count();
    let sh = shader::Shader {
        g: &g,
        setups: &setups,
        ngs: &ngs,
        mats: setup::prepare_materials(&g, opts.mipmaps),
        lights,
        eye: cam.eye,
        forward: cam.frame().map_err(|e| RasterError::Camera(e.into()))?[2],
        opts,
        progress,
    };
    let out = resolve::resolve_bands(&sh, &bins, cam, s, opts, triangles);
    // The big buffers go back to the pools for the next render (`scratch`).
    for lp in sh.lights {
        scratch::FACTORS.give(lp.factors);
        if let Some(map) = lp.map {
            map.recycle();
        }
    }
    scratch::SETUPS.give(setups);
    scratch::NORMALS.give(ngs);
    scratch::give_geometry(g);
    Ok(out)
}

/// The bytes `render` allocates for its buffers: 16 per pixel and produced pass, the
/// visibility buffer of the bands in flight (8 bytes per sample, one band per thread) and the
/// shadow maps (4 bytes per texel, a point light's six half-size faces counted as 1.5 maps).
/// Saturates instead of overflowing; checked with `ExecContext::reserve_bytes` before rendering.
pub fn raster_bytes(cam: &Camera, opts: &RasterOptions, lights: usize) -> u64 {
    use cgnodes_api::node::bytes_of;
    let p = opts.passes;
    let passes = [p.color, p.depth, p.normal, p.position, p.uv, p.base_color]
        .iter()
        .filter(|&&on| on)
        .count() as u64;
    let (w, h, s) = (
        cam.width as u64,
        cam.height as u64,
        opts.samples_per_axis.clamp(1, 8) as u64,
    );
    let images = bytes_of(&[w, h, passes, 16]);
    let threads = rayon::current_num_threads() as u64;
    let bands = bytes_of(&[w, s, resolve::BAND_PX as u64, s, 8, threads]);
    let res = opts.shadow_resolution.clamp(16, 8192) as u64;
    let shadows = if p.color && opts.shadows {
        bytes_of(&[lights as u64, res, res, 6])
    } else {
        0
    };
    images.saturating_add(bands).saturating_add(shadows)
}

/// Registers `render_raster`.
pub fn register(r: &mut Registry) {
    render_raster::register(r);
}
