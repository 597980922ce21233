//! The four-lane arithmetic of `path_lanes`: one path per SSE lane (`wide::f32x4`), vectors
//! stored axis by axis (`[axis][lane]`), and the lane forms of `sampling`'s functions, each
//! performing the scalar function's floating-point operations in the same order so that a
//! lane's result is the scalar one bit for bit.

use super::render_scene::OFFSET_REL;
use super::sampling::{SERIES_RECIPROCALS, V3};
use std::f32::consts::FRAC_PI_4;
use wide::f32x4;

/// Paths in flight (one per SSE lane).
pub(super) const L: usize = 4;

/// Four floats, one per path.
pub(super) type F = f32x4;
/// A 3-vector per lane, axis by axis.
pub(super) type F3 = [F; 3];

/// Per-lane vector sum.
#[inline(always)]
pub(super) fn add3(a: F3, b: F3) -> F3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
/// Per-lane vector difference.
#[inline(always)]
pub(super) fn sub3(a: F3, b: F3) -> F3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
/// Per-lane product, axis by axis.
#[inline(always)]
pub(super) fn mul3(a: F3, b: F3) -> F3 {
    [a[0] * b[0], a[1] * b[1], a[2] * b[2]]
}
/// Per-lane vector times a per-lane scalar.
#[inline(always)]
pub(super) fn scale3(a: F3, s: F) -> F3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
/// Per-lane dot product.
#[inline(always)]
pub(super) fn dot3(a: F3, b: F3) -> F {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
/// `a[0].max(a[1]).max(a[2])` per lane (`max` returns the other operand on NaN, as
/// `f32::max` does).
#[inline(always)]
pub(super) fn max3(a: F3) -> F {
    a[0].max(a[1]).max(a[2])
}
/// `m ? a : b` per lane.
#[inline(always)]
pub(super) fn sel3(m: F, a: F3, b: F3) -> F3 {
    [
        m.select(a[0], b[0]),
        m.select(a[1], b[1]),
        m.select(a[2], b[2]),
    ]
}
/// `x` in every lane.
#[inline(always)]
pub(super) fn splat(x: f32) -> F {
    F::splat(x)
}
/// The lanes where `m` is set, as the low four bits.
#[inline(always)]
pub(super) fn bits(m: F) -> u32 {
    m.to_bitmask()
}
/// `RenderScene::offset` per lane.
#[inline(always)]
pub(super) fn offset4(eps: f32, p: F3, n: F3) -> F3 {
    let m = p[0].abs().max(p[1].abs()).max(p[2].abs());
    add3(p, scale3(n, splat(eps) + splat(OFFSET_REL) * m))
}

/// `sampling::power_heuristic` per lane.
#[inline(always)]
pub(super) fn power4(pa: F, pb: F) -> F {
    let a = pa * pa;
    let b = pb * pb;
    let s = a + b;
    let first = s.simd_gt(splat(0.0)) & a.is_finite();
    first.select(a / s, a.is_inf().select(splat(1.0), splat(0.0)))
}

/// `sampling::sin_cos_quarter` per lane (the same series, the same operation order).
#[inline(always)]
pub(super) fn sin_cos_quarter4(a: F) -> (F, F) {
    let one = splat(1.0);
    let a2 = a * a;
    let r = SERIES_RECIPROCALS.map(splat);
    let s = a * (one - a2 * r[0] * (one - a2 * r[1] * (one - a2 * r[2])));
    let c = one - a2 * splat(0.5) * (one - a2 * r[3] * (one - a2 * r[4] * (one - a2 * r[5])));
    (s, c)
}

/// `sampling::cosine_hemisphere` per lane: the orthonormal basis of Duff et al. 2017 and
/// Malley's method over the concentric map, both branches computed and selected.
#[inline(always)]
pub(super) fn cosine_hemisphere4(n: F3, u: [F; 2]) -> F3 {
    let one = splat(1.0);
    let sign = n[2].is_sign_negative().select(splat(-1.0), one);
    let a = splat(-1.0) / (sign + n[2]);
    let b = n[0] * n[1] * a;
    let t = [one + sign * n[0] * n[0] * a, sign * b, -sign * n[0]];
    let bt = [b, sign + n[1] * n[1] * a, -n[1]];
    let two = splat(2.0);
    let ox = two * u[0] - one;
    let oy = two * u[1] - one;
    let zero = splat(0.0);
    let origin = ox.simd_eq(zero) & oy.simd_eq(zero);
    // Each lane evaluates the series once, at its own branch's angle.
    let wide_x = ox.abs().simd_gt(oy.abs());
    let ratio = wide_x.select(oy, ox) / wide_x.select(ox, oy);
    let (sn, cs) = sin_cos_quarter4(splat(FRAC_PI_4) * ratio);
    let x = wide_x.select(ox * cs, oy * sn);
    let y = wide_x.select(ox * sn, oy * cs);
    let x = origin.select(zero, x);
    let y = origin.select(zero, y);
    let z = (one - x * x - y * y).max(zero).sqrt();
    add3(add3(scale3(t, x), scale3(bt, y)), scale3(n, z))
}

/// A lane row as a register.
#[inline(always)]
pub(super) fn f4(a: &[f32; L]) -> F {
    F::new(*a)
}
/// A `[axis][lane]` vector as registers.
#[inline(always)]
pub(super) fn f43(a: &[[f32; L]; 3]) -> F3 {
    [f4(&a[0]), f4(&a[1]), f4(&a[2])]
}
/// Registers back into a `[axis][lane]` vector.
#[inline(always)]
pub(super) fn store3(a: &mut [[f32; L]; 3], v: F3) {
    for k in 0..3 {
        a[k] = v[k].to_array();
    }
}
/// Sets lane `i` of a `[axis][lane]` vector.
#[inline(always)]
pub(super) fn put(a: &mut [[f32; L]; 3], i: usize, v: V3) {
    a[0][i] = v[0];
    a[1][i] = v[1];
    a[2][i] = v[2];
}
/// Lane `i` of a `[axis][lane]` vector.
#[inline(always)]
pub(super) fn get(a: &[[f32; L]; 3], i: usize) -> V3 {
    [a[0][i], a[1][i], a[2][i]]
}
