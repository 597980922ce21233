//! Per-triangle isometric local frames, Jacobians and the closed-form 2x2 decompositions
//! shared by ARAP, ASAP and the hybrid (Liu et al. 2008, "A Local/Global Approach to Mesh
//! Parameterization", §3).
//!
//! Each triangle is laid flat in its own 2-D frame without distortion (corner 0 at the origin,
//! edge 0→1 on the x axis, corner 2 above it), so the map from that frame to the UV plane is
//! linear with Jacobian `J = [u1-u0, u2-u0] · [x1-x0, x2-x0]^-1`.

use super::error::ArapError;
use cgnodes_api::types::vec3::{cross, cross2, dot, norm, sub, sub2};
use rayon::prelude::*;

/// Triangles per rayon task: large enough that small meshes run on one thread and the
/// per-task overhead stays negligible.
pub const PAR_CHUNK: usize = 2048;

/// A 2x2 matrix, row-major: `[[a, b], [c, d]]`.
pub type Mat2 = [[f64; 2]; 2];

/// Everything about the 3-D triangles that the iterations reuse.
#[derive(Clone, Debug)]
pub struct TriangleFrames {
    /// Triangle vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// Area of each 3-D triangle.
    pub area: Vec<f64>,
    /// Sum of the areas.
    pub total_area: f64,
    /// Corners in the local isometric frame (`x0 = 0`, `x1 = (|e01|, 0)`, `x2.y > 0`).
    pub local: Vec<[[f64; 2]; 3]>,
    /// `[x1-x0, x2-x0]^-1`, which is upper triangular: `[[p, q], [0, r]]` stored as `[p, q, r]`.
    pub inv_edges: Vec<[f64; 3]>,
    /// Cotangent of the angle at each corner (weight of the opposite edge).
    pub cot: Vec<[f64; 3]>,
}

impl TriangleFrames {
    /// Builds the frames; fails on a triangle with zero or non-finite area, naming it.
    pub fn new(
        positions: &[[f64; 3]],
        triangles: &[[u32; 3]],
    ) -> Result<TriangleFrames, ArapError> {
        let n = positions.len();
        type Frame = ([[f64; 2]; 3], f64, [f64; 3], [f64; 3]);
        let per: Vec<Result<Frame, ArapError>> = triangles
            .par_iter()
            .with_min_len(PAR_CHUNK)
            .enumerate()
            .map(|(t, tri)| {
                if tri.iter().any(|&v| v as usize >= n) {
                    return Err(ArapError::VertexOutOfRange(t));
                }
                let p = tri.map(|v| positions[v as usize]);
                let e1 = sub(p[1], p[0]);
                let e2 = sub(p[2], p[0]);
                let l1 = norm(e1);
                let cr = norm(cross(e1, e2));
                let area = 0.5 * cr;
                let scale = dot(e1, e1).max(dot(e2, e2));
                if !(area.is_finite() && l1 > 0.0 && cr > 1e-14 * scale) {
                    return Err(ArapError::DegenerateTriangle {
                        triangle: t,
                        vertices: *tri,
                    });
                }
                let x = [[0.0, 0.0], [l1, 0.0], [dot(e1, e2) / l1, cr / l1]];
                // inverse of [[l1, x2x], [0, x2y]]
                let inv = [1.0 / l1, -x[2][0] / (l1 * x[2][1]), 1.0 / x[2][1]];
                let mut cot = [0.0; 3];
                for (k, c) in cot.iter_mut().enumerate() {
                    let a = sub2(x[(k + 1) % 3], x[k]);
                    let b = sub2(x[(k + 2) % 3], x[k]);
                    *c = (a[0] * b[0] + a[1] * b[1]) / cr;
                }
                Ok((x, area, inv, cot))
            })
            .collect();
        let mut f = TriangleFrames {
            triangles: triangles.to_vec(),
            area: Vec::with_capacity(triangles.len()),
            total_area: 0.0,
            local: Vec::with_capacity(triangles.len()),
            inv_edges: Vec::with_capacity(triangles.len()),
            cot: Vec::with_capacity(triangles.len()),
        };
        for r in per {
            let (x, a, inv, cot) = r?;
            f.local.push(x);
            f.area.push(a);
            f.inv_edges.push(inv);
            f.cot.push(cot);
        }
        f.total_area = f.area.iter().sum();
        Ok(f)
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The Jacobian of triangle `t` under the UVs `uv`.
    // `always`, here and on the local step's helpers below: when the loop that calls them moved
    // to its own module (issue 22), LLVM stopped inlining them into the per-triangle closure and
    // an ARAP iteration on camelhead went from 0.96 to 1.24 ms (`bench/arap.rs`, 2026-12-01).
    #[inline(always)]
    pub fn jacobian(&self, t: usize, uv: &[[f64; 2]]) -> Mat2 {
        let [e1, e2] = self.edges(t, uv);
        self.jacobian_of_edges(t, e1, e2)
    }

    /// The UV edges `u1 - u0` and `u2 - u0` of triangle `t`.
    #[inline]
    pub fn edges(&self, t: usize, uv: &[[f64; 2]]) -> [[f64; 2]; 2] {
        let [i, j, k] = self.triangles[t];
        let u0 = uv[i as usize];
        [sub2(uv[j as usize], u0), sub2(uv[k as usize], u0)]
    }

    /// The Jacobian of triangle `t` from its UV edges (`edges`).
    #[inline]
    pub fn jacobian_of_edges(&self, t: usize, u1: [f64; 2], u2: [f64; 2]) -> Mat2 {
        let [p, q, r] = self.inv_edges[t];
        [
            [u1[0] * p, u1[0] * q + u2[0] * r],
            [u1[1] * p, u1[1] * q + u2[1] * r],
        ]
    }

    /// Twice the signed UV area of triangle `t` (positive when counter-clockwise).
    #[inline]
    pub fn signed_area2(&self, t: usize, uv: &[[f64; 2]]) -> f64 {
        let [i, j, k] = self.triangles[t];
        let u0 = uv[i as usize];
        cross2(sub2(uv[j as usize], u0), sub2(uv[k as usize], u0))
    }
}

/// The similarity part `(E, H)` and the anti-similarity part `(F, G)` of `J`:
/// `J = [[E, -H], [H, E]] + [[F, G], [G, -F]]`. The singular values are
/// `sqrt(E²+H²) ± sqrt(F²+G²)` (closed-form 2x2 SVD), the second signed like `det J`.
#[inline(always)]
pub fn similarity_parts(j: &Mat2) -> (f64, f64, f64, f64) {
    let e = 0.5 * (j[0][0] + j[1][1]);
    let h = 0.5 * (j[1][0] - j[0][1]);
    let f = 0.5 * (j[0][0] - j[1][1]);
    let g = 0.5 * (j[0][1] + j[1][0]);
    (e, h, f, g)
}

/// Signed singular values `(s1, s2)` of a 2x2 matrix, `s1 >= |s2|`, `s2 < 0` when `det < 0`.
#[inline(always)]
pub fn signed_singular_values(j: &Mat2) -> (f64, f64) {
    let (e, h, f, g) = similarity_parts(j);
    let q = norm2(e, h);
    let r = norm2(f, g);
    (q + r, q - r)
}

/// `sqrt(a² + b²)`: the plain formula (libm's `hypot` is much slower in the hot loops),
/// falling back to `hypot` when the squares overflow or underflow.
#[inline(always)]
pub fn norm2(a: f64, b: f64) -> f64 {
    let s = a * a + b * b;
    if s.is_normal() {
        s.sqrt()
    } else {
        a.hypot(b)
    }
}

/// The target map of the local step, `L = s·R(θ)`, stored as `[s cos θ, s sin θ]`.
pub type Similarity = [f64; 2];

/// Local step of Liu et al. 2008 for one triangle: the rotation (`lambda = None`, ARAP, §4.1),
/// or the scaled rotation minimising `|J - sR|² + 2λ(s²-1)²` (hybrid, §4.3; `lambda = 0` is
/// ASAP's similarity). Returns the target and `|J - L|² + 2λ(s²-1)²`, the triangle's energy
/// per unit area at the optimum.
#[inline(always)]
pub fn local_step(j: &Mat2, lambda: Option<f64>) -> (Similarity, f64) {
    let (e, h, _, _) = similarity_parts(j);
    let q = norm2(e, h);
    let (c, s_) = if q > 0.0 { (e / q, h / q) } else { (1.0, 0.0) };
    let s = match lambda {
        None => 1.0,
        Some(l) => hybrid_scale(q, l),
    };
    let pen = match lambda {
        None => 0.0,
        Some(l) => 2.0 * l * (s * s - 1.0).powi(2),
    };
    let l = [s * c, s * s_];
    // |J - L|², summed entry by entry (no cancellation near the optimum)
    let energy = (j[0][0] - l[0]).powi(2)
        + (j[0][1] + l[1]).powi(2)
        + (j[1][0] - l[1]).powi(2)
        + (j[1][1] - l[0]).powi(2)
        + pen;
    (l, energy)
}

/// The scale of the hybrid model: the minimiser over `s >= 0` of
/// `g(s) = 2s² - 4sq + 2λ(s²-1)²`, a root of the cubic `2λ s³ + (1-2λ) s - q = 0`
/// (Liu et al. 2008, eq. 10 in our normalisation).
pub fn hybrid_scale(q: f64, lambda: f64) -> f64 {
    if lambda <= 0.0 {
        return q;
    }
    let g = |s: f64| 2.0 * s * s - 4.0 * s * q + 2.0 * lambda * (s * s - 1.0).powi(2);
    // depressed cubic s³ + p s + r = 0
    let p = (1.0 - 2.0 * lambda) / (2.0 * lambda);
    let r = -q / (2.0 * lambda);
    let mut best = (g(0.0), 0.0);
    for s in cubic_real_roots(p, r) {
        if s >= 0.0 && s.is_finite() {
            // one Newton polish on h(s) = 2λs³ + (1-2λ)s - q
            let h = 2.0 * lambda * s * s * s + (1.0 - 2.0 * lambda) * s - q;
            let dh = 6.0 * lambda * s * s + 1.0 - 2.0 * lambda;
            let s = if dh.abs() > 1e-12 { s - h / dh } else { s };
            let s = s.max(0.0);
            if g(s) < best.0 {
                best = (g(s), s);
            }
        }
    }
    best.1
}

/// Real roots of `s³ + p s + r = 0` (Cardano, trigonometric form for three roots).
fn cubic_real_roots(p: f64, r: f64) -> Vec<f64> {
    let disc = (r / 2.0).powi(2) + (p / 3.0).powi(3);
    if disc > 0.0 {
        let sq = disc.sqrt();
        vec![(-r / 2.0 + sq).cbrt() + (-r / 2.0 - sq).cbrt()]
    } else if p == 0.0 {
        vec![0.0]
    } else {
        let m = 2.0 * (-p / 3.0).sqrt();
        let arg = (3.0 * r / (p * m)).clamp(-1.0, 1.0);
        let theta = arg.acos() / 3.0;
        (0..3)
            .map(|k| m * (theta - 2.0 * std::f64::consts::PI * k as f64 / 3.0).cos())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn singular_values_match_nalgebra() {
        for j in [
            [[1.0, 2.0], [3.0, 4.0]],
            [[0.3, -1.2], [0.7, 0.1]],
            [[2.0, 0.0], [0.0, -0.5]],
        ] {
            let m = nalgebra::Matrix2::new(j[0][0], j[0][1], j[1][0], j[1][1]);
            let sv = m.singular_values();
            let (s1, s2) = signed_singular_values(&j);
            assert!((s1 - sv.max()).abs() < 1e-12);
            assert!((s2.abs() - sv.min()).abs() < 1e-12);
            assert_eq!(s2 < 0.0, m.determinant() < 0.0);
        }
    }

    #[test]
    fn local_step_energy_is_distance_to_the_target() {
        let j = [[0.3, -1.2], [0.7, 0.1]];
        for lambda in [None, Some(0.0), Some(0.5), Some(3.0)] {
            let (l, e) = local_step(&j, lambda);
            let lm = [[l[0], -l[1]], [l[1], l[0]]];
            let s2 = l[0] * l[0] + l[1] * l[1];
            let d: f64 = (0..2)
                .flat_map(|a| (0..2).map(move |b| (a, b)))
                .map(|(a, b)| (j[a][b] - lm[a][b]).powi(2))
                .sum();
            let pen = lambda.map_or(0.0, |lm| 2.0 * lm * (s2 - 1.0).powi(2));
            assert!((d + pen - e).abs() < 1e-12, "{lambda:?}");
            // no scaled rotation nearby does better
            for ds in [-1e-3, 1e-3] {
                for da in [-1e-3, 1e-3] {
                    let s = s2.sqrt() + ds;
                    let a = l[1].atan2(l[0]) + da;
                    let lm2 = [[s * a.cos(), -s * a.sin()], [s * a.sin(), s * a.cos()]];
                    let d2: f64 = (0..2)
                        .flat_map(|x| (0..2).map(move |y| (x, y)))
                        .map(|(x, y)| (j[x][y] - lm2[x][y]).powi(2))
                        .sum();
                    let e2 = match lambda {
                        None => {
                            if ds != 0.0 {
                                continue;
                            }
                            d2
                        }
                        Some(lm) => d2 + 2.0 * lm * (s * s - 1.0).powi(2),
                    };
                    assert!(e2 >= e - 1e-12);
                }
            }
        }
    }

    #[test]
    fn hybrid_scale_limits() {
        // λ = 0 gives the similarity (ASAP), large λ a rotation (ARAP)
        assert!((hybrid_scale(0.7, 0.0) - 0.7).abs() < 1e-15);
        assert!((hybrid_scale(0.7, 1e8) - 1.0).abs() < 1e-6);
        assert!((hybrid_scale(1.0, 2.0) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn equilateral_frame() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.75f64.sqrt(), 0.0]];
        let f = TriangleFrames::new(&p, &[[0, 1, 2]]).unwrap();
        assert!((f.area[0] - 3f64.sqrt() / 4.0).abs() < 1e-15);
        for c in f.cot[0] {
            assert!((c - 1.0 / 3f64.sqrt()).abs() < 1e-12);
        }
        let uv: Vec<[f64; 2]> = p.iter().map(|q| [q[0], q[1]]).collect();
        let j = f.jacobian(0, &uv);
        assert!((j[0][0] - 1.0).abs() < 1e-12 && j[0][1].abs() < 1e-12);
        assert!(TriangleFrames::new(&p, &[[0, 1, 1]]).is_err());
    }
}
