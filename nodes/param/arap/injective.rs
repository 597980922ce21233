//! Fold-free line search: the largest step along a search direction that keeps every
//! triangle's orientation (Smith & Schaefer 2015, "Bijective Parameterization with Free
//! Boundaries", §4), and flip counting.

use super::frames::{TriangleFrames, PAR_CHUNK};
use cgnodes_api::types::vec3::cross2;
use rayon::prelude::*;

/// The smallest positive `t` at which triangle `t`'s signed area, moving as `uv + t·d`,
/// reaches zero (`f64::INFINITY` if never). `orient` is `+1` or `-1`, the orientation to keep.
///
/// Twice the signed area is the quadratic `c0 + c1 t + c2 t²` in `t` (Smith & Schaefer 2015,
/// eq. 5), solved with the cancellation-free form of the quadratic formula.
#[inline]
pub fn triangle_max_step(
    frames: &TriangleFrames,
    t: usize,
    uv: &[[f64; 2]],
    d: &[[f64; 2]],
    orient: f64,
) -> f64 {
    triangle_max_step_above(frames, t, uv, d, orient, 0.0)
}

/// Like `triangle_max_step`, but the smallest positive `t` at which twice the signed area
/// drops to `floor2` (the fold-free ARAP keeps a margin so triangles are not squeezed flat).
#[inline]
pub fn triangle_max_step_above(
    frames: &TriangleFrames,
    t: usize,
    uv: &[[f64; 2]],
    d: &[[f64; 2]],
    orient: f64,
    floor2: f64,
) -> f64 {
    let [a, b] = frames.edges(t, uv);
    let [da, db] = frames.edges(t, d);
    max_step_of_edges([a, b], [da, db], orient, floor2)
}

/// `triangle_max_step_above` from the triangle's UV edges `[u1 - u0, u2 - u0]` and the
/// direction's `[d1 - d0, d2 - d0]`.
#[inline]
pub fn max_step_of_edges(e: [[f64; 2]; 2], de: [[f64; 2]; 2], orient: f64, floor2: f64) -> f64 {
    let [c0, c1, c2] = area_coefficients(e, de, orient, floor2);
    smallest_positive_root(c0, c1, c2)
}

/// `[c0, c1, c2]` with `c0 + c1 t + c2 t²` twice the signed area (times `orient`) minus
/// `floor2` of the triangle with UV edges `e` moving along edge directions `de` by `t`
/// (Smith & Schaefer 2015, eq. 5).
#[inline]
pub fn area_coefficients(
    e: [[f64; 2]; 2],
    de: [[f64; 2]; 2],
    orient: f64,
    floor2: f64,
) -> [f64; 3] {
    let ([a, b], [da, db]) = (e, de);
    [
        orient * cross2(a, b) - floor2,
        orient * (cross2(a, db) + cross2(da, b)),
        orient * cross2(da, db),
    ]
}

/// Smallest positive root of `c0 + c1 t + c2 t²` (`INFINITY` if none); `0` when `c0 <= 0`.
///
/// Without data-dependent branches (a negative discriminant gives NaN roots, which the
/// `r > 0` selection drops like infinite ones), so that in a loop of these the square root
/// and divisions of successive calls overlap.
#[inline]
pub fn smallest_positive_root(c0: f64, c1: f64, c2: f64) -> f64 {
    let disc = c1 * c1 - 4.0 * c2 * c0;
    let q = -0.5 * (c1 + disc.sqrt().copysign(c1));
    let positive = |r: f64| if r > 0.0 { r } else { f64::INFINITY };
    let best = positive(q / c2).min(positive(c0 / q));
    if c0 <= 0.0 {
        0.0
    } else {
        best
    }
}

/// The largest step along `d` that keeps every triangle's orientation `orient`
/// (the minimum over triangles of `triangle_max_step`), in parallel.
pub fn max_step(frames: &TriangleFrames, uv: &[[f64; 2]], d: &[[f64; 2]], orient: f64) -> f64 {
    (0..frames.len())
        .into_par_iter()
        .with_min_len(PAR_CHUNK)
        .map(|t| triangle_max_step(frames, t, uv, d, orient))
        .reduce(|| f64::INFINITY, f64::min)
}

/// The majority orientation of the UV triangles (`+1` counter-clockwise, `-1` clockwise)
/// and the number of triangles that disagree with it or are degenerate.
pub fn orientation_and_flips(frames: &TriangleFrames, uv: &[[f64; 2]]) -> (f64, usize) {
    let (pos, neg) = (0..frames.len())
        .into_par_iter()
        .with_min_len(PAR_CHUNK)
        .map(|t| {
            let a = frames.signed_area2(t, uv);
            (usize::from(a > 0.0), usize::from(a < 0.0))
        })
        .reduce(|| (0, 0), |x, y| (x.0 + y.0, x.1 + y.1));
    if pos >= neg {
        (1.0, frames.len() - pos)
    } else {
        (-1.0, frames.len() - neg)
    }
}

/// Number of triangles whose UV orientation is not `orient` (degenerate ones included).
pub fn count_flips(frames: &TriangleFrames, uv: &[[f64; 2]], orient: f64) -> usize {
    (0..frames.len())
        .into_par_iter()
        .with_min_len(PAR_CHUNK)
        .filter(|&t| orient * frames.signed_area2(t, uv) <= 0.0)
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roots() {
        // (1 - t)(1 - t/2) = 1 - 1.5 t + 0.5 t² -> first zero at 1
        assert!((smallest_positive_root(1.0, -1.5, 0.5) - 1.0).abs() < 1e-15);
        // linear: 2 - 4t -> 0.5
        assert!((smallest_positive_root(2.0, -4.0, 0.0) - 0.5).abs() < 1e-15);
        // never zero for t > 0
        assert_eq!(smallest_positive_root(1.0, 1.0, 1.0), f64::INFINITY);
        assert_eq!(smallest_positive_root(1.0, 0.0, 0.0), f64::INFINITY);
        assert_eq!(smallest_positive_root(-1.0, 1.0, 0.0), 0.0);
    }

    #[test]
    fn step_stops_where_the_triangle_flattens() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let f = TriangleFrames::new(&p, &[[0, 1, 2]]).unwrap();
        let uv = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        // move the apex down by 4: flat at t = 0.25
        let d = [[0.0, 0.0], [0.0, 0.0], [0.0, -4.0]];
        assert!((max_step(&f, &uv, &d, 1.0) - 0.25).abs() < 1e-15);
        let moved: Vec<[f64; 2]> = (0..3)
            .map(|i| [uv[i][0] + 0.3 * d[i][0], uv[i][1] + 0.3 * d[i][1]])
            .collect();
        assert_eq!(count_flips(&f, &moved, 1.0), 1);
        assert_eq!(orientation_and_flips(&f, &uv), (1.0, 0));
    }
}
