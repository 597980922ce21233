//! `ssao`: screen-space ambient occlusion (Mittring, "Finding Next Gen: CryEngine 2",
//! SIGGRAPH 2007 course; in the normal-oriented hemisphere form of Chapman's "SSAO" tutorial
//! and LearnOpenGL that the course's `ssao.fs` points to), Framework3D's `render_ssao`.
//!
//! For a surface pixel at world position `p` with normal `n`, `N` kernel points `s_i` of
//! the unit hemisphere around +z (denser near the centre: lengths scaled by
//! `lerp(0.1, 1, (i/N)^2)`) are turned into the frame `(t, b, n)`, where `t` comes from a
//! 4 x 4 tile of random tangent directions (Gram-Schmidt against `n`), and placed at
//! `q_i = p + R (t, b, n) s_i` for the radius `R`. Each `q_i` is projected by the camera;
//! it is occluded when the depth buffer there is nearer than its own depth minus a bias,
//! weighted by the range check `smoothstep(0, 1, R / |z_p - z_buffer|)`, so that far
//! occluders do not darken. The buffer is read through the tangent plane (position and
//! normal) of the pixel `q_i` lands in, at `q_i`'s own ray, so a plane gives its exact depth
//! there and surfaces seen at grazing angles do not occlude themselves between pixel
//! centres (a departure from reading the nearest depth texel). `AO = 1 - (sum of weights) / N`, then averaged over a 4 x 4
//! box of surface pixels (the tile's size) to remove the tile's pattern. Samples that leave
//! the image or land on background do not occlude. Without a normal pass the normal is
//! reconstructed from the position pass (cross product of the screen-space differences
//! with the nearer neighbour on each axis). Without a camera (Framework3D's node has no
//! camera socket) the camera is recovered from the position and depth passes
//! (`camera_from_gbuffer`).

use super::{check_size, depth_hit, is_surface, pass_camera};
use cgnodes_api::prelude::*;
use cgnodes_api::rng::Pcg32;
use cgnodes_api::types::vec3::{axpy, cross, dot, normalize, sub};

/// SSAO settings.
#[derive(Clone, Debug)]
pub struct SsaoParams {
    /// Hemisphere radius `R`, in world units.
    pub radius: f64,
    /// Kernel points `N`.
    pub samples: u32,
    /// Depth bias against self-occlusion, in world units.
    pub bias: f64,
    /// Average over a 4 x 4 box of surface pixels.
    pub blur: bool,
}

impl Default for SsaoParams {
    fn default() -> Self {
        SsaoParams {
            radius: 0.5,
            samples: 16,
            bias: 0.025,
            blur: true,
        }
    }
}

/// The hemisphere kernel (`n` points, +z up) and the 4 x 4 tile of tangent directions
/// (x, y in the camera's right and up axes), deterministic.
fn kernel(n: u32) -> (Vec<[f64; 3]>, [[f64; 2]; 16]) {
    let mut rng = Pcg32::new(0x55a0, 7);
    let mut f = || rng.next_f32() as f64;
    let pts = (0..n)
        .map(|i| {
            let d = normalize([2.0 * f() - 1.0, 2.0 * f() - 1.0, 0.05 + 0.95 * f()])
                .unwrap_or([0.0, 0.0, 1.0]);
            let t = (i as f64 + f()) / n as f64;
            let s = (0.1 + 0.9 * t * t) * (0.5 + 0.5 * f());
            d.map(|c| c * s)
        })
        .collect();
    let tile = std::array::from_fn(|_| [2.0 * f() - 1.0, 2.0 * f() - 1.0]);
    (pts, tile)
}

fn smoothstep(x: f64) -> f64 {
    let t = x.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

fn px3(p: [f32; 4]) -> [f64; 3] {
    [p[0] as f64, p[1] as f64, p[2] as f64]
}

/// Normals from the position pass: the cross product of the screen-space differences
/// taken towards the neighbour nearer in depth on each axis, facing the eye.
pub fn normals_from_positions(position: &Image, eye: [f64; 3]) -> Image {
    let (w, h) = (position.width, position.height);
    super::image_from_fn(w, h, |x, y| {
        let c = position.get(x, y);
        if !is_surface(c) {
            return [0.0; 4];
        }
        let p = px3(c);
        let diff = |a: Option<(u32, u32)>, b: Option<(u32, u32)>, sign: f64| {
            let pick = |q: Option<(u32, u32)>| {
                q.map(|(qx, qy)| position.get(qx, qy))
                    .filter(|v| is_surface(*v))
                    .map(px3)
            };
            match (pick(a), pick(b)) {
                (Some(u), Some(v)) => {
                    let (du, dv) = (sub(u, p), sub(p, v));
                    Some(if dot(du, du) <= dot(dv, dv) { du } else { dv })
                }
                (Some(u), None) => Some(sub(u, p)),
                (None, Some(v)) => Some(sub(p, v)),
                (None, None) => None,
            }
            .map(|d| d.map(|c| c * sign))
        };
        let dx = diff(
            (x + 1 < w).then_some((x + 1, y)),
            x.checked_sub(1).map(|xm| (xm, y)),
            1.0,
        );
        let dy = diff(
            (y + 1 < h).then_some((x, y + 1)),
            y.checked_sub(1).map(|ym| (x, ym)),
            1.0,
        );
        let (Some(dx), Some(dy)) = (dx, dy) else {
            return [0.0; 4];
        };
        let Some(mut n) = normalize(cross(dx, dy)) else {
            return [0.0; 4];
        };
        if dot(n, sub(eye, p)) < 0.0 {
            n = n.map(|c| -c);
        }
        [n[0] as f32, n[1] as f32, n[2] as f32, 1.0]
    })
}

/// Ambient occlusion (1 open, 0 closed; see the module doc) of the surface pixels of
/// `position` seen from `cam`; `normal` and `depth` are computed from the positions when
/// absent. Non-surface pixels get 1. Output is grey with alpha 1.
pub fn ssao(
    position: &Image,
    normal: Option<&Image>,
    depth: Option<&Image>,
    cam: &Camera,
    par: &SsaoParams,
) -> Image {
    let (w, h) = (position.width, position.height);
    let look = cam.look_at::<f64>();
    let own_normals;
    let normal = match normal {
        Some(n) => n,
        None => {
            own_normals = normals_from_positions(position, cam.eye);
            &own_normals
        }
    };
    let (pts, tile) = kernel(par.samples.max(1));
    let pass = SsaoPass {
        position,
        normal,
        zbuf: depth_buffer(position, depth, &look),
        look,
        f: cam.focal_length_px(),
        cam,
        par,
        pts,
        tile,
    };
    let raw = super::image_from_fn(w, h, |x, y| pass.pixel(x, y));
    if !par.blur {
        return raw.with_opaque();
    }
    tile_blur(&raw)
}

/// The depth buffer SSAO compares against: the depth pass, or view depths of the positions
/// (0 = nothing).
fn depth_buffer(position: &Image, depth: Option<&Image>, look: &LookAt<f64>) -> Vec<f64> {
    match depth {
        Some(d) => d
            .pixels
            .iter()
            .map(|&v| if depth_hit(v) { v[0] as f64 } else { 0.0 })
            .collect(),
        None => position
            .pixels
            .iter()
            .map(|&v| {
                if is_surface(v) {
                    look.to_view(px3(v))[2]
                } else {
                    0.0
                }
            })
            .collect(),
    }
}

/// The tangent `t` of the kernel frame at normal `n`: the tile's random direction `tv` (in
/// the camera's right and up axes) made orthogonal to `n` (Gram-Schmidt), or any
/// perpendicular when it is parallel to `n`.
fn kernel_tangent(n: [f64; 3], tv: [f64; 2], look: &LookAt<f64>) -> [f64; 3] {
    let rv = axpy(look.right.map(|c| c * tv[0]), tv[1], look.up);
    normalize(axpy(rv, -dot(rv, n), n))
        .or_else(|| {
            let a = if n[0].abs() < 0.9 {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 1.0, 0.0]
            };
            normalize(cross(a, n))
        })
        .unwrap_or([1.0, 0.0, 0.0])
}

/// One SSAO evaluation over a G-buffer: the passes, the camera, the kernel and its tile.
struct SsaoPass<'a> {
    position: &'a Image,
    normal: &'a Image,
    /// View depth per pixel, 0 where nothing was hit.
    zbuf: Vec<f64>,
    look: LookAt<f64>,
    /// Focal length in pixels.
    f: f64,
    cam: &'a Camera,
    par: &'a SsaoParams,
    /// The hemisphere kernel (+z up).
    pts: Vec<[f64; 3]>,
    /// The 4 x 4 tile of tangent directions.
    tile: [[f64; 2]; 16],
}

impl SsaoPass<'_> {
    /// The unblurred AO of pixel `(x, y)` as grey, with alpha 0 on non-surface pixels (so
    /// the blur skips them).
    fn pixel(&self, x: u32, y: u32) -> [f32; 4] {
        let pp = self.position.get(x, y);
        let nn = self.normal.get(x, y);
        let Some(n) = normalize(px3(nn)).filter(|_| is_surface(pp)) else {
            return [1.0, 1.0, 1.0, 0.0];
        };
        let p = px3(pp);
        let zp = self.look.to_view(p)[2];
        let tv = self.tile[(y as usize % 4) * 4 + x as usize % 4];
        let t = kernel_tangent(n, tv, &self.look);
        let b = cross(n, t);
        let r = self.par.radius;
        let mut occ = 0.0;
        for s in &self.pts {
            let off = axpy(axpy(t.map(|c| c * s[0]), s[1], b), s[2], n);
            let q = axpy(p, r, off);
            if let Some(o) = self.occlusion(q, zp) {
                occ += o;
            }
        }
        let ao = (1.0 - occ / self.pts.len() as f64) as f32;
        [ao, ao, ao, 1.0]
    }

    /// The occlusion weight of kernel point `q` for a pixel at view depth `zp`: `None` when
    /// `q` is behind the near plane, leaves the image, lands on background or is not
    /// occluded; else the range check's weight.
    fn occlusion(&self, q: [f64; 3], zp: f64) -> Option<f64> {
        let (w, h) = (self.position.width, self.position.height);
        let (cam, f) = (self.cam, self.f);
        let v = self.look.to_view(q);
        if v[2] <= cam.near {
            return None;
        }
        let sx = 0.5 * w as f64 + f * v[0] / v[2];
        let sy = 0.5 * h as f64 - f * v[1] / v[2];
        if !(sx >= 0.0 && sy >= 0.0 && sx < w as f64 && sy < h as f64) {
            return None;
        }
        let (ix, iy) = (sx as u32, sy as u32);
        let mut zb = self.zbuf[iy as usize * w as usize + ix as usize];
        if zb <= 0.0 {
            return None;
        }
        // Read the buffer through the tangent plane of the pixel q lands in.
        if let Some(m) = normalize(px3(self.normal.get(ix, iy))) {
            let dq = sub(q, cam.eye);
            let den = dot(dq, m);
            let tq = dot(sub(px3(self.position.get(ix, iy)), cam.eye), m) / den;
            if den.abs() > 1e-12 && tq > 0.0 && tq.is_finite() {
                zb = tq * v[2];
            }
        }
        (zb <= v[2] - self.par.bias)
            .then(|| smoothstep(self.par.radius / (zp - zb).abs().max(1e-12)))
    }
}

/// The 4 x 4 box average of the surface pixels of `raw` (alpha > 0), the tile's size, which
/// removes the tile's pattern; non-surface pixels get 1.
fn tile_blur(raw: &Image) -> Image {
    let (w, h) = (raw.width, raw.height);
    super::image_from_fn(w, h, |x, y| {
        if raw.get(x, y)[3] == 0.0 {
            return [1.0; 4];
        }
        let (mut s, mut k) = (0.0f32, 0u32);
        for dy in -2i64..2 {
            for dx in -2i64..2 {
                let (qx, qy) = (x as i64 + dx, y as i64 + dy);
                if qx < 0 || qy < 0 || qx >= w as i64 || qy >= h as i64 {
                    continue;
                }
                let v = raw.get(qx as u32, qy as u32);
                if v[3] > 0.0 {
                    s += v[0];
                    k += 1;
                }
            }
        }
        let a = s / k.max(1) as f32;
        [a, a, a, 1.0]
    })
}

trait Opaque {
    fn with_opaque(self) -> Self;
}
impl Opaque for Image {
    fn with_opaque(mut self) -> Image {
        for p in &mut self.pixels {
            p[3] = 1.0;
        }
        self
    }
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Screen-space ambient occlusion from a G-buffer (Framework3D's render_ssao): a normal-oriented hemisphere kernel with a range check.");
    b.add_input::<Image>("color")
        .optional()
        .doc("Colour to darken (output color = color x ao); without it, color is the ao.");
    b.add_input::<Image>("position")
        .doc("World-space position pass.");
    b.add_input::<Image>("depth")
        .optional()
        .doc("Depth pass (else computed from the positions).");
    b.add_input::<Image>("normal")
        .optional()
        .doc("World-space normal pass (else reconstructed from the positions).");
    b.add_input::<Camera>("camera")
        .optional()
        .doc("The camera the G-buffer was rendered with (else recovered from position and depth).");
    let d = SsaoParams::default();
    b.add_input::<f64>("radius")
        .default(d.radius)
        .range(1e-6, 1e6)
        .doc("Hemisphere radius in world units.");
    b.add_input::<i64>("samples")
        .default(d.samples as i64)
        .range(1.0, 256.0)
        .doc("Kernel points per pixel.");
    b.add_input::<f64>("bias")
        .default(d.bias)
        .range(0.0, 1e6)
        .doc("Depth bias in world units (against self-occlusion).");
    b.add_input::<bool>("blur")
        .default(d.blur)
        .doc("Average the AO over 4x4 pixels (hides the kernel rotation pattern).");
    b.add_output::<Image>("color")
        .doc("The colour times the AO.");
    b.add_output::<Image>("ao")
        .doc("Ambient occlusion, 1 open to 0 closed (grey).");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let position: Arc<Image> = ctx.input("position")?;
    let (w, h) = (position.width, position.height);
    check_size("position", &position, w, h)?;
    let color: Option<Arc<Image>> = ctx.input_opt("color")?;
    let depth: Option<Arc<Image>> = ctx.input_opt("depth")?;
    let normal: Option<Arc<Image>> = ctx.input_opt("normal")?;
    for (n, img) in [("color", &color), ("depth", &depth), ("normal", &normal)] {
        if let Some(i) = img {
            check_size(n, i, w, h)?;
        }
    }
    let cam = match (ctx.input_opt::<Arc<Camera>>("camera")?, &depth) {
        (Some(c), _) => pass_camera(Some(c), None, w, h)?,
        (None, Some(d)) => {
            let c = super::camera_from_gbuffer(&position, d).map_err(|e| {
                NodeError::invalid("camera", format!("not linked, and not recoverable: {e}"))
            })?;
            ctx.log(format!(
                "camera recovered from the position and depth passes: eye {:.4?}, fov {:.3} degrees",
                c.eye, c.fov_deg
            ));
            c
        }
        (None, None) => {
            return Err(NodeError::invalid(
                "camera",
                "link the G-buffer's camera, or the depth pass to recover it from",
            ))
        }
    };
    // Ranges (NaN refused) are checked by the runtime from the declaration.
    let radius: f64 = ctx.input("radius")?;
    let bias: f64 = ctx.input("bias")?;
    let samples: i64 = ctx.input("samples")?;
    let par = SsaoParams {
        radius,
        samples: samples as u32,
        bias,
        blur: ctx.input("blur")?,
    };
    let ao = ssao(&position, normal.as_deref(), depth.as_deref(), &cam, &par);
    let out = match &color {
        Some(c) => {
            let mut o = (**c).clone();
            for (p, a) in o.pixels.iter_mut().zip(&ao.pixels) {
                for c in p.iter_mut().take(3) {
                    *c *= a[0];
                }
            }
            o
        }
        None => ao.clone(),
    };
    ctx.set_output("color", out);
    ctx.set_output("ao", ao);
    Ok(())
}

/// Registers `ssao`.
pub fn register(r: &mut Registry) {
    r.add("ssao", declare, execute);
}
