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

pub use crate::raster::light_at;
use cgnodes_api::prelude::*;
use cgnodes_api::types::vec3::{dot, normalize_recip as normalize, sub};
use cgnodes_api::types::LookAt;
use cgnodes_geometry::environment::Environment;

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
    if (img.width, img.height) != (w, h) || img.pixels.len() != w as usize * h as usize {
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

/// Why `camera_from_gbuffer` cannot recover a camera.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CameraFitError {
    /// Fewer than three pixels are surfaces in both passes.
    #[error("fewer than three surface pixels to recover the camera from")]
    TooFewSurfaces,
    /// The least-squares solve failed (nalgebra's SVD message).
    #[error("{0}")]
    Solve(&'static str),
    /// The fitted image-plane axes are degenerate.
    #[error("the pixels do not span the image plane")]
    NotSpanning,
    /// The positions are off the best pinhole camera by more than 1e-3 of the extent.
    #[error("the passes do not fit one pinhole camera (residual {residual:.3e} against extent {extent:.3e})")]
    NotPinhole { residual: f64, extent: f64 },
}

/// The pinhole camera a position and depth pass were rendered with, recovered by linear
/// least squares, for passes whose camera is not linked (Framework3D's `render_ssao` has no
/// camera socket). A surface pixel at `(x', y')` from the image centre (x right, y up) with
/// view depth `z` lies at `P = e + z (x' a + y' b + c)`, with `a = right / f`,
/// `b = up / f` (`f` the focal length in pixels) and `c` the viewing direction. The fit
/// solves for `(e + z c, a, b)` per coordinate (SVD of the 4 x 4 normal equations, which
/// are singular when every depth is the same, e.g. a plane facing the camera, without
/// disturbing `a` and `b`), then takes `c = b x a` normalized and `e` as the mean of
/// `P - z (x' a + y' b + c)`. Fails when fewer than three pixels are surfaces or the
/// positions do not fit one pinhole camera (residual above 1e-3 of the scene's extent).
pub fn camera_from_gbuffer(position: &Image, depth: &Image) -> Result<Camera, CameraFitError> {
    use nalgebra::{Matrix4, Vector4};
    let (w, h) = (position.width, position.height);
    let mut samples = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let (p, d) = (position.get(x, y), depth.get(x, y));
            if is_surface(p) && depth_hit(d) && d[0] > 0.0 {
                let xs = x as f64 + 0.5 - 0.5 * w as f64;
                let ys = 0.5 * h as f64 - y as f64 - 0.5;
                samples.push(([p[0] as f64, p[1] as f64, p[2] as f64], xs, ys, d[0] as f64));
            }
        }
    }
    if samples.len() < 3 {
        return Err(CameraFitError::TooFewSurfaces);
    }
    let mut ata = Matrix4::<f64>::zeros();
    let mut atp = [Vector4::<f64>::zeros(); 3];
    for (p, xs, ys, z) in &samples {
        let row = Vector4::new(1.0, z * xs, z * ys, *z);
        ata += row * row.transpose();
        for k in 0..3 {
            atp[k] += row * p[k];
        }
    }
    let svd = ata.svd(true, true);
    let eps = 1e-12 * svd.singular_values.max();
    let mut a = [0.0; 3];
    let mut b = [0.0; 3];
    for k in 0..3 {
        let t = svd.solve(&atp[k], eps).map_err(CameraFitError::Solve)?;
        a[k] = t[1];
        b[k] = t[2];
    }
    let (fa, fb) = (dot(a, a).sqrt(), dot(b, b).sqrt());
    let c = cgnodes_api::types::vec3::cross(b, a);
    let Some(c) = normalize(c).filter(|_| fa > 0.0 && fb > 0.0) else {
        return Err(CameraFitError::NotSpanning);
    };
    let point = |xs: f64, ys: f64, z: f64| -> [f64; 3] {
        std::array::from_fn(|k| z * (xs * a[k] + ys * b[k] + c[k]))
    };
    let mut e = [0.0; 3];
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for (p, xs, ys, z) in &samples {
        let q = point(*xs, *ys, *z);
        for k in 0..3 {
            e[k] += (p[k] - q[k]) / samples.len() as f64;
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let extent = dot(sub(hi, lo), sub(hi, lo)).sqrt().max(1e-12);
    let (mut zmin, mut zmax, mut worst) = (f64::INFINITY, 0.0f64, 0.0f64);
    for (p, xs, ys, z) in &samples {
        let q = point(*xs, *ys, *z);
        let r = sub(*p, std::array::from_fn(|k| e[k] + q[k]));
        worst = worst.max(dot(r, r).sqrt());
        zmin = zmin.min(*z);
        zmax = zmax.max(*z);
    }
    if worst.is_nan() || worst > 1e-3 * extent {
        return Err(CameraFitError::NotPinhole {
            residual: worst,
            extent,
        });
    }
    let f = 2.0 / (fa + fb);
    let up = b.map(|v| v / fb);
    Ok(Camera {
        eye: e,
        target: std::array::from_fn(|k| e[k] + c[k]),
        up,
        fov_deg: 2.0 * (0.5 * h as f64 / f).atan().to_degrees(),
        fov_axis: cgnodes_api::types::FovAxis::Vertical,
        width: w,
        height: h,
        near: (0.5 * zmin).max(1e-9),
        far: (2.0 * zmax).max(1.0),
    })
}

/// The unit world direction of the camera ray through the centre of pixel `(x, y)` (row 0
/// at the top), as the tracers and the rasterizer's projection define it (`Camera`).
#[inline]
pub fn camera_ray(look: &LookAt<f64>, focal_px: f64, w: u32, h: u32, x: u32, y: u32) -> [f64; 3] {
    let sx = (x as f64 + 0.5 - 0.5 * w as f64) / focal_px;
    let sy = (0.5 * h as f64 - y as f64 - 0.5) / focal_px;
    look.ray_dir(sx, sy)
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
pub fn image_from_fn(w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 4] + Sync) -> Image {
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
