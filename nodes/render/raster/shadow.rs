//! Shadow maps (Williams, "Casting Curved Shadows on Curved Surfaces", SIGGRAPH 1978).
//!
//! A directional light gets one orthographic depth map fitted to the scene's bounding box;
//! a point light gets a cube map (six 90-degree perspective faces), so shadows fall in
//! every direction around it. Lookups use a slope-scaled depth bias against self-shadowing
//! "acne" and percentage-closer filtering (Reeves, Salesin and Cook, SIGGRAPH 1987): the
//! fraction of `(2r+1)^2` neighbouring texels whose depth test passes.
//!
//! Bias, in units of the world size `tau` of one texel at the receiver:
//! `bias = tau * (c0 + c1 * tan(theta) * (r + 1))`, where `theta` is the angle between
//! the geometric normal and the light. A planar receiver's depth changes by
//! `tau * tan(theta)` per texel, and PCF compares against texels up to `(r + 1/2) sqrt 2`
//! texels away, so `c1 >= 1.5` keeps every lit plane free of acne.

use super::rasterize::{rasterize_into, setup_triangle};
use super::scratch::{DEPTHS, SETUPS};
use cgnodes_api::types::vec3::{cross, dot, sub, unit};
use rayon::prelude::*;

/// Bias and filtering settings of a shadow lookup.
#[derive(Clone, Copy, Debug)]
pub struct ShadowParams {
    /// PCF radius r: (2r+1)^2 taps.
    pub pcf_radius: u32,
    /// Constant bias c0, in texels.
    pub bias: f64,
    /// Slope bias c1, in texels per unit of tan(theta) and PCF ring.
    pub slope_bias: f64,
}

impl Default for ShadowParams {
    /// One PCF ring, a one-texel constant bias and 1.5 texels of slope bias: the defaults of
    /// `render_raster` and `deferred_lighting`.
    fn default() -> Self {
        ShadowParams {
            pcf_radius: 1,
            bias: 1.0,
            slope_bias: 1.5,
        }
    }
}

/// One square depth map with a projection into it.
#[derive(Clone, Debug)]
pub struct Face {
    /// Light-space axes (right, up, forward).
    pub axes: [[f64; 3]; 3],
    /// Origin of the light space.
    pub origin: [f64; 3],
    /// Depth per texel, row-major from the top.
    pub depth: Vec<f32>,
}

/// A light's shadow map.
#[derive(Clone, Debug)]
pub enum ShadowMap {
    /// Orthographic map: pixel `((x - x0) k, (y1 - y) k)` for light-space `(x, y)`.
    Directional {
        /// The map.
        face: Box<Face>,
        /// Left and top of the fitted window.
        x0: f64,
        /// Top of the window.
        y1: f64,
        /// Pixels per world unit.
        k: f64,
        /// Resolution.
        res: u32,
    },
    /// Cube map around a point light: faces +X, -X, +Y, -Y, +Z, -Z.
    Point {
        /// The six faces.
        faces: Box<[Face; 6]>,
        /// Face resolution.
        res: u32,
    },
}

/// The orthographic frame of a directional light's shadow map: light-space axes
/// `[right, up, forward]` for light travelling along `dir`, and the window fitted to the box
/// `bounds` (left `x0`, top `y1`, `k` pixels per world unit at `res` x `res`). Shared by
/// `directional_shadow_map` and the G-buffer passes, which rebuild a map from its depths.
pub(crate) fn directional_frame(
    dir: [f64; 3],
    bounds: ([f64; 3], [f64; 3]),
    res: u32,
) -> ([[f64; 3]; 3], f64, f64, f64) {
    let f = unit(dir);
    let a = if f[1].abs() > 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let r = unit(cross(f, a));
    let u = cross(r, f);
    let (lo, hi) = bounds;
    let mut x0 = f64::INFINITY;
    let mut x1 = f64::NEG_INFINITY;
    let mut y0 = f64::INFINITY;
    let mut y1 = f64::NEG_INFINITY;
    for c in 0..8 {
        let p = [
            if c & 1 == 0 { lo[0] } else { hi[0] },
            if c & 2 == 0 { lo[1] } else { hi[1] },
            if c & 4 == 0 { lo[2] } else { hi[2] },
        ];
        let (x, y) = (dot(p, r), dot(p, u));
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let ext = (x1 - x0).max(y1 - y0).max(1e-9);
    let pad = 0.01 * ext;
    let (x0, y1) = (x0 - pad, y1 + pad);
    let k = res as f64 / (ext + 2.0 * pad);
    ([r, u, f], x0, y1, k)
}

/// Builds an orthographic shadow map for light travelling along `dir`, fitted to the box
/// `bounds` (so every triangle casts), at `res` x `res`.
pub fn directional_shadow_map(
    tris: &[[[f64; 3]; 3]],
    dir: [f64; 3],
    bounds: ([f64; 3], [f64; 3]),
    res: u32,
) -> ShadowMap {
    let ([r, u, f], x0, y1, k) = directional_frame(dir, bounds, res);
    // Setups and depths in buffers kept from earlier renders (`scratch`).
    let mut setups = SETUPS.take(tris.len());
    tris.par_iter()
        .map(|t| {
            let h = t.map(|p| [(dot(p, r) - x0) * k, (y1 - dot(p, u)) * k, 1.0]);
            setup_triangle(h, t.map(|p| dot(p, f)), 0.5, res, res)
        })
        .collect_into_vec(&mut setups);
    let n = res as usize * res as usize;
    let target = rasterize_into(
        &setups,
        res,
        res,
        f64::NEG_INFINITY,
        f64::INFINITY,
        false,
        DEPTHS.take(n),
    );
    SETUPS.give(setups);
    ShadowMap::Directional {
        face: Box::new(Face {
            axes: [r, u, f],
            origin: [0.0; 3],
            depth: target.depth,
        }),
        x0,
        y1,
        k,
        res,
    }
}

/// The axes `[right, up, forward]` of a cube map's faces +X, -X, +Y, -Y, +Z, -Z.
pub(crate) fn cube_axes() -> [[[f64; 3]; 3]; 6] {
    let fw = [
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    fw.map(|f| {
        let up = if f[1] != 0.0 {
            [0.0, 0.0, 1.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let r = cross(f, up);
        [r, up, f]
    })
}

/// Builds a cube shadow map around a point light at `pos`, six faces of `res` x `res`.
/// `near` is the closest distance a caster may have (triangles nearer are cut).
pub fn point_shadow_map(tris: &[[[f64; 3]; 3]], pos: [f64; 3], res: u32, near: f64) -> ShadowMap {
    let half = res as f64 * 0.5;
    let faces = cube_axes().map(|[r, u, f]| {
        let mut setups = SETUPS.take(tris.len());
        tris.par_iter()
            .map(|t| {
                let c = t.map(|p| {
                    let d = sub(p, pos);
                    [dot(d, r), dot(d, u), dot(d, f)]
                });
                if c.iter().all(|v| v[2] < near) {
                    return None;
                }
                let h = c.map(|v| [half * v[2] + half * v[0], half * v[2] - half * v[1], v[2]]);
                setup_triangle(h, c.map(|v| v[2]), near, res, res)
            })
            .collect_into_vec(&mut setups);
        let n = res as usize * res as usize;
        let target = rasterize_into(
            &setups,
            res,
            res,
            near,
            f64::INFINITY,
            false,
            DEPTHS.take(n),
        );
        SETUPS.give(setups);
        Face {
            axes: [r, u, f],
            origin: pos,
            depth: target.depth,
        }
    });
    ShadowMap::Point {
        faces: Box::new(faces),
        res,
    }
}

/// Percentage-closer filter over a face: the fraction of taps around pixel `(x, y)` whose
/// stored depth is not nearer than `z - bias`. Taps off the map count as lit
/// (directional) or clamp to the edge (cube faces).
#[allow(clippy::too_many_arguments)]
fn pcf(depth: &[f32], res: u32, x: f64, y: f64, z: f64, bias: f64, r: i64, clamp: bool) -> f64 {
    let (cx, cy) = (floor_i64(x), floor_i64(y));
    let n = res as i64;
    let zt = (z - bias) as f32;
    if r == 1 && cx >= 1 && cy >= 1 && cx + 1 < n && cy + 1 < n {
        // The default 3x3 window, on the map: three rows of three taps, no loops.
        let (n, i) = (n as usize, ((cy - 1) * n + cx - 1) as usize);
        let row = |k: usize| {
            let t = &depth[k..k + 3];
            (t[0] >= zt) as u32 + (t[1] >= zt) as u32 + (t[2] >= zt) as u32
        };
        let lit = row(i) + row(i + n) + row(i + 2 * n);
        return lit as f64 / 9.0;
    }
    if cx - r >= 0 && cy - r >= 0 && cx + r < n && cy + r < n {
        // The whole window lies on the map: no clamping or bounds tests per tap.
        let mut lit = 0usize;
        for ty in cy - r..=cy + r {
            let row = (ty * n) as usize;
            let taps = &depth[row + (cx - r) as usize..=row + (cx + r) as usize];
            lit += taps.iter().filter(|&&d| d >= zt).count();
        }
        let side = 2 * r as usize + 1;
        return lit as f64 / (side * side) as f64;
    }
    let mut lit = 0u32;
    let mut total = 0u32;
    for dy in -r..=r {
        for dx in -r..=r {
            let (mut tx, mut ty) = (cx + dx, cy + dy);
            total += 1;
            if clamp {
                tx = tx.clamp(0, n - 1);
                ty = ty.clamp(0, n - 1);
            } else if tx < 0 || ty < 0 || tx >= n || ty >= n {
                lit += 1;
                continue;
            }
            if depth[(ty * n + tx) as usize] >= zt {
                lit += 1;
            }
        }
    }
    lit as f64 / total as f64
}

/// `x.floor() as i64` without the libm call (the baseline x86-64 target has no SSE4.1
/// rounding instruction, and this runs twice per shadow lookup).
#[inline]
fn floor_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// The bias of a lookup in texel sizes, `c0 + c1 tan(theta) (r + 1)` (see the module doc),
/// for unit geometric normal `ng` (either side) and unit direction to the light `l`. It
/// depends on the triangle and the light only, so the rasterizer computes it once per
/// triangle for directional lights (`ShadowMap::visibility_with`).
pub fn bias_factor(ng: [f64; 3], l: [f64; 3], sp: &ShadowParams) -> f64 {
    let c = dot(ng, l).abs().clamp(1e-3, 1.0);
    let tan = ((1.0 - c * c).sqrt() / c).min(10.0);
    let r = sp.pcf_radius as i64;
    sp.bias + sp.slope_bias * tan * (r as f64 + 1.0)
}

impl ShadowMap {
    /// Fraction of the light reaching point `p` with geometric normal `ng` (unit, facing
    /// the light side) and unit direction to the light `l`: 1 lit, 0 in shadow.
    pub fn visibility(&self, p: [f64; 3], ng: [f64; 3], l: [f64; 3], sp: &ShadowParams) -> f64 {
        self.visibility_with(p, bias_factor(ng, l, sp), sp.pcf_radius)
    }

    /// Gives the depth buffers back to the rasterizer's pool (`scratch`) for the next render.
    pub(super) fn recycle(self) {
        match self {
            ShadowMap::Directional { face, .. } => DEPTHS.give(face.depth),
            ShadowMap::Point { faces, .. } => {
                for f in *faces {
                    DEPTHS.give(f.depth);
                }
            }
        }
    }

    /// `visibility` with the bias factor of `bias_factor` given, and PCF radius `pcf_radius`.
    pub fn visibility_with(&self, p: [f64; 3], factor: f64, pcf_radius: u32) -> f64 {
        let r = pcf_radius as i64;
        let slope = |tau: f64| tau * factor;
        match self {
            ShadowMap::Directional {
                face,
                x0,
                y1,
                k,
                res,
            } => {
                let [ax, ay, az] = face.axes;
                let x = (dot(p, ax) - x0) * k;
                let y = (y1 - dot(p, ay)) * k;
                pcf(
                    &face.depth,
                    *res,
                    x,
                    y,
                    dot(p, az),
                    slope(1.0 / k),
                    r,
                    false,
                )
            }
            ShadowMap::Point { faces, res } => {
                let d = sub(p, faces[0].origin);
                let a = d.map(f64::abs);
                let fi = if a[0] >= a[1] && a[0] >= a[2] {
                    if d[0] >= 0.0 {
                        0
                    } else {
                        1
                    }
                } else if a[1] >= a[2] {
                    if d[1] >= 0.0 {
                        2
                    } else {
                        3
                    }
                } else if d[2] >= 0.0 {
                    4
                } else {
                    5
                };
                let face = &faces[fi];
                let [ax, ay, az] = face.axes;
                let z = dot(d, az);
                if z <= 0.0 {
                    return 1.0;
                }
                let half = *res as f64 * 0.5;
                let x = half + half * dot(d, ax) / z;
                let y = half - half * dot(d, ay) / z;
                pcf(
                    &face.depth,
                    *res,
                    x,
                    y,
                    z,
                    slope(2.0 * z / *res as f64),
                    r,
                    true,
                )
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(y: f64, h: f64) -> Vec<[[f64; 3]; 3]> {
        let a = [-h, y, -h];
        let b = [h, y, -h];
        let c = [h, y, h];
        let d = [-h, y, h];
        vec![[a, c, b], [a, d, c]]
    }

    const P: ShadowParams = ShadowParams {
        pcf_radius: 1,
        bias: 1.0,
        slope_bias: 1.5,
    };

    #[test]
    fn directional_occluder_shadows_the_ground_below_it_only() {
        // Ground 4x4 at y = 0, occluder 1x1 at y = 1, light straight down.
        let mut tris = quad(0.0, 2.0);
        tris.extend(quad(1.0, 0.5));
        let bounds = ([-2.0, 0.0, -2.0], [2.0, 1.0, 2.0]);
        let sm = directional_shadow_map(&tris, [0.0, -1.0, 0.0], bounds, 256);
        let up = [0.0, 1.0, 0.0];
        assert_eq!(sm.visibility([0.0, 0.0, 0.0], up, up, &P), 0.0);
        assert_eq!(sm.visibility([1.5, 0.0, 1.5], up, up, &P), 1.0);
        // The occluder's own top is lit.
        assert_eq!(sm.visibility([0.1, 1.0, 0.2], up, up, &P), 1.0);
    }

    #[test]
    fn slanted_lit_plane_has_no_acne() {
        // A lone ground plane lit at 60 degrees from the normal: every point is lit.
        let tris = quad(0.0, 2.0);
        let dir = unit([3f64.sqrt(), -1.0, 0.3]);
        let l = dir.map(|v| -v);
        let bounds = ([-2.0, 0.0, -2.0], [2.0, 0.0, 2.0]);
        for res in [256, 1024] {
            let sm = directional_shadow_map(&tris, dir, bounds, res);
            for i in 0..40 {
                for j in 0..40 {
                    let p = [
                        -1.95 + 0.1 * i as f64,
                        0.0,
                        -1.95 + 0.1 * j as f64 + 0.001 * i as f64,
                    ];
                    assert_eq!(sm.visibility(p, [0.0, 1.0, 0.0], l, &P), 1.0, "{p:?}");
                }
            }
        }
    }

    #[test]
    fn point_light_cube_map_shadows_in_every_direction() {
        // Light at the origin inside a box of six walls; a small blocker on the +X side.
        let mut tris = Vec::new();
        for s in [-1.0, 1.0] {
            // Walls at x = 2s, y = 2s, z = 2s.
            let w = 2.0 * s;
            tris.push([[w, -2.0, -2.0], [w, 2.0, -2.0], [w, 2.0, 2.0]]);
            tris.push([[w, -2.0, -2.0], [w, 2.0, 2.0], [w, -2.0, 2.0]]);
            tris.push([[-2.0, w, -2.0], [2.0, w, -2.0], [2.0, w, 2.0]]);
            tris.push([[-2.0, w, -2.0], [2.0, w, 2.0], [-2.0, w, 2.0]]);
            tris.push([[-2.0, -2.0, w], [2.0, -2.0, w], [2.0, 2.0, w]]);
            tris.push([[-2.0, -2.0, w], [2.0, 2.0, w], [-2.0, 2.0, w]]);
        }
        tris.push([[1.0, -0.3, -0.3], [1.0, 0.3, -0.3], [1.0, 0.3, 0.3]]);
        tris.push([[1.0, -0.3, -0.3], [1.0, 0.3, 0.3], [1.0, -0.3, 0.3]]);
        let sm = point_shadow_map(&tris, [0.0; 3], 256, 1e-3);
        let lit = |p: [f64; 3], n: [f64; 3]| {
            let l = unit(sub([0.0; 3], p));
            sm.visibility(p, n, l, &P)
        };
        assert_eq!(lit([2.0, 0.0, 0.0], [-1.0, 0.0, 0.0]), 0.0);
        assert_eq!(lit([2.0, 1.5, 1.5], [-1.0, 0.0, 0.0]), 1.0);
        for (p, n) in [
            ([-2.0, 0.3, 0.1], [1.0, 0.0, 0.0]),
            ([0.2, 2.0, -0.5], [0.0, -1.0, 0.0]),
            ([0.2, -2.0, 0.5], [0.0, 1.0, 0.0]),
            ([0.7, 0.1, 2.0], [0.0, 0.0, -1.0]),
            ([-0.7, -0.1, -2.0], [0.0, 0.0, 1.0]),
        ] {
            assert_eq!(lit(p, n), 1.0, "{p:?}");
        }
    }
}
