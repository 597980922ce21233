//! G-buffer passes: Framework3D's deferred render passes (USTC CG 2024,
//! `Framework3D/source/nodes/nodes/render/`: `render_deferred_lighting`,
//! `render_shadow_mapping`, `render_ssao`, `render_environment_pass`,
//! `render_transparent_refraction` and their shaders `blinn_phong.fs`, `shadow_mapping.fs`,
//! `ssao.fs`, `environment_map.fs`, `transparent_refraction.fs`) computed on the CPU over the
//! passes `render_raster` writes (position, depth, normal, base colour). One pass per file,
//! each a plain function over images (callable without the runtime) and a thin node.
//!
//! Conventions shared with `render_raster`: a G-buffer pixel is a surface where its alpha
//! is above 0 (and, for depth, its value is not 0, the course shaders' test); positions
//! and normals are world-space; depth is the distance along the viewing direction.

pub mod deferred_lighting;
pub mod environment_pass;
pub mod shadow_mapping;
pub mod ssao;
pub mod transparent_refraction;

use crate::nodes::trace::environment::Environment;
use crate::prelude::*;
use crate::types::vec3::{dot, normalize_recip as normalize, sub};
use crate::types::LookAt;

/// Whether a position, normal or base-colour pixel holds a surface (alpha above 0).
#[inline]
pub fn is_surface(px: [f32; 4]) -> bool {
    px[3] > 0.0
}

/// Whether a depth pixel holds a surface: alpha above 0 and depth not 0 (the course
/// shaders' `depth_val == 0` test for "nothing was hit").
#[inline]
pub fn depth_hit(px: [f32; 4]) -> bool {
    px[3] > 0.0 && px[0] != 0.0 && px[0].is_finite()
}

/// Fails naming `socket` unless `img` is `w` x `h` (all passes of one G-buffer share a size).
pub fn check_size(socket: &str, img: &Image, w: u32, h: u32) -> Result<(), NodeError> {
    if (img.width, img.height) != (w, h)
        || img.pixels.len() != w as usize * h as usize
    {
        return Err(NodeError::invalid(
            socket,
            format!(
                "is {}x{} but the G-buffer is {w}x{h}; connect passes of one render",
                img.width, img.height
            ),
        ));
    }
    Ok(())
}

/// The camera of a pass: the `camera` input, else the scene's camera, else an error naming
/// `camera`. The camera is checked (`Camera::check`) and its resolution must be `w` x `h`.
pub fn pass_camera(
    cam: Option<Arc<Camera>>,
    scene: Option<&Scene>,
    w: u32,
    h: u32,
) -> Result<Camera, NodeError> {
    let cam = match (cam, scene.and_then(|s| s.camera.as_ref())) {
        (Some(c), _) => (*c).clone(),
        (None, Some(c)) => c.clone(),
        (None, None) => {
            return Err(NodeError::invalid(
                "camera",
                "no camera: connect the camera the G-buffer was rendered with",
            ))
        }
    };
    cam.check().map_err(|e| NodeError::invalid("camera", e))?;
    if (cam.width, cam.height) != (w, h) {
        return Err(NodeError::invalid(
            "camera",
            format!(
                "renders {}x{} but the G-buffer is {w}x{h}",
                cam.width, cam.height
            ),
        ));
    }
    Ok(cam)
}

/// The unit world direction of the camera ray through the centre of pixel `(x, y)` (row 0
/// at the top), as the tracers and the rasterizer's projection define it (`Camera`).
#[inline]
pub fn camera_ray(look: &LookAt<f64>, focal_px: f64, w: u32, h: u32, x: u32, y: u32) -> [f64; 3] {
    let sx = (x as f64 + 0.5 - 0.5 * w as f64) / focal_px;
    let sy = (0.5 * h as f64 - y as f64 - 0.5) / focal_px;
    look.ray_dir(sx, sy)
}

/// Unit direction from `p` towards a point or directional light and the irradiance it
/// gives there (colour times intensity, over the squared distance for a point light), as
/// the rasterizer lights a surface; `None` for environment lights and degenerate ones.
pub fn light_at(light: &Light, p: [f64; 3]) -> Option<([f64; 3], [f64; 3])> {
    match light {
        Light::Directional {
            direction,
            color,
            intensity,
        } => normalize(*direction).map(|d| (d.map(|c| -c), color.map(|c| c * intensity))),
        Light::Point {
            position,
            color,
            intensity,
        } => {
            let d = sub(*position, p);
            let r2 = dot(d, d);
            normalize(d).map(|l| (l, color.map(|c| c * intensity / r2)))
        }
        Light::Environment { .. } => None,
    }
}

/// What a camera ray sees when it leaves the scene: the scene's first environment light
/// (equirectangular with rotation, the tracers' mapping in `nodes/trace/environment.rs`),
/// or a constant fallback colour when the scene has none.
pub struct Sky {
    env: Option<Environment>,
    fallback: [f64; 3],
}

impl Sky {
    /// The sky of `lights`; `fallback` where there is no environment light.
    pub fn new(lights: &[Light], fallback: [f64; 3]) -> Sky {
        Sky {
            env: Environment::from_lights(lights),
            fallback,
        }
    }

    /// Whether an environment light was found.
    pub fn has_environment(&self) -> bool {
        self.env.is_some()
    }

    /// Radiance arriving along `-d` from world direction `d` (unit).
    pub fn eval(&self, d: [f64; 3]) -> [f64; 3] {
        match &self.env {
            Some(e) => e
                .eval([d[0] as f32, d[1] as f32, d[2] as f32])
                .map(|c| c as f64),
            None => self.fallback,
        }
    }
}

/// An image of `w` x `h` whose rows are filled in parallel by `f(x, y)`.
pub fn image_from_fn(
    w: u32,
    h: u32,
    f: impl Fn(u32, u32) -> [f32; 4] + Sync,
) -> Image {
    use rayon::prelude::*;
    let mut img = Image::new(w, h, [0.0; 4]);
    if w > 0 {
        img.pixels
            .par_chunks_mut(w as usize)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, px) in row.iter_mut().enumerate() {
                    *px = f(x as u32, y as u32);
                }
            });
    }
    img
}

/// `[f64; 3]` to an opaque pixel.
#[inline]
pub fn rgb1(c: [f64; 3]) -> [f32; 4] {
    [c[0] as f32, c[1] as f32, c[2] as f32, 1.0]
}

/// Registers the G-buffer pass nodes.
pub fn register(r: &mut Registry) {
    deferred_lighting::register(r);
    environment_pass::register(r);
    shadow_mapping::register(r);
    ssao::register(r);
    transparent_refraction::register(r);
}
