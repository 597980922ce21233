//! The lane arithmetic of `path_lanes`: one path per lane of eight, vectors stored axis by
//! axis (`[axis][lane]`), and the lane forms of `sampling`'s functions, each performing the
//! scalar function's floating-point operations in the same order so that a lane's result
//! is the scalar one bit for bit. The lanes are a `Lane`: `wide::f32x8` (two SSE halves) in
//! the baseline build, `lane_avx::Avx8` (one 256-bit register) in the x86-64-v3 one.

use super::render_scene::OFFSET_REL;
use super::sampling::{SERIES_RECIPROCALS, V3};
use std::f32::consts::FRAC_PI_4;
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};
use wide::f32x8;

/// Paths in flight (one per lane).
pub(super) const L: usize = 8;

/// Eight floats, one per path, with `wide`'s operations and their exact results: IEEE
/// arithmetic, masks of all ones or zeros, `max` returning `self` when `rhs` is NaN.
pub(super) trait Lane:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + Not<Output = Self>
    + Neg<Output = Self>
{
    /// `x` in every lane.
    fn splat(x: f32) -> Self;
    /// The lanes of `a`.
    fn from_array(a: [f32; L]) -> Self;
    /// The lanes as an array.
    fn to_array(self) -> [f32; L];
    /// Per lane `self ? t : f`, `self` a mask.
    fn select(self, t: Self, f: Self) -> Self;
    /// Mask of `self == rhs` (false on NaN).
    fn simd_eq(self, rhs: Self) -> Self;
    /// Mask of `self != rhs` (true on NaN).
    fn simd_ne(self, rhs: Self) -> Self;
    /// Mask of `self < rhs`.
    fn simd_lt(self, rhs: Self) -> Self;
    /// Mask of `self <= rhs`.
    fn simd_le(self, rhs: Self) -> Self;
    /// Mask of `self > rhs`.
    fn simd_gt(self, rhs: Self) -> Self;
    /// `f32::max` per lane (the other operand where one is NaN).
    fn max(self, rhs: Self) -> Self;
    /// Absolute value (sign bit cleared).
    fn abs(self) -> Self;
    /// Correctly rounded square root.
    fn sqrt(self) -> Self;
    /// Mask of the finite lanes.
    fn is_finite(self) -> Self;
    /// Mask of the infinite lanes.
    fn is_inf(self) -> Self;
    /// Mask of the lanes whose sign bit is set.
    fn is_sign_negative(self) -> Self;
    /// The lanes where the mask is set, as the low eight bits.
    fn to_bitmask(self) -> u32;
}

/// `Lane` methods that are `f32x8`'s inherent ones of the same name and signature.
macro_rules! inherent {
    ($($f:ident($($a:ident: $t:ty),*) -> $r:ty;)*) => {$(
        #[inline(always)]
        fn $f(self, $($a: $t),*) -> $r {
            f32x8::$f(self, $($a),*)
        }
    )*};
}

impl Lane for f32x8 {
    #[inline(always)]
    fn splat(x: f32) -> Self {
        f32x8::splat(x)
    }
    #[inline(always)]
    fn from_array(a: [f32; L]) -> Self {
        f32x8::new(a)
    }
    inherent! {
        to_array() -> [f32; L];
        select(t: Self, f: Self) -> Self;
        simd_eq(rhs: Self) -> Self;
        simd_ne(rhs: Self) -> Self;
        simd_lt(rhs: Self) -> Self;
        simd_le(rhs: Self) -> Self;
        simd_gt(rhs: Self) -> Self;
        max(rhs: Self) -> Self;
        abs() -> Self;
        sqrt() -> Self;
        is_finite() -> Self;
        is_inf() -> Self;
        is_sign_negative() -> Self;
        to_bitmask() -> u32;
    }
}

/// A 3-vector per lane, axis by axis.
pub(super) type F3<F> = [F; 3];

/// Per-lane vector sum.
#[inline(always)]
pub(super) fn add3<F: Lane>(a: F3<F>, b: F3<F>) -> F3<F> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
/// Per-lane vector difference.
#[inline(always)]
pub(super) fn sub3<F: Lane>(a: F3<F>, b: F3<F>) -> F3<F> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
/// Per-lane product, axis by axis.
#[inline(always)]
pub(super) fn mul3<F: Lane>(a: F3<F>, b: F3<F>) -> F3<F> {
    [a[0] * b[0], a[1] * b[1], a[2] * b[2]]
}
/// Per-lane vector times a per-lane scalar.
#[inline(always)]
pub(super) fn scale3<F: Lane>(a: F3<F>, s: F) -> F3<F> {
    [a[0] * s, a[1] * s, a[2] * s]
}
/// Per-lane dot product.
#[inline(always)]
pub(super) fn dot3<F: Lane>(a: F3<F>, b: F3<F>) -> F {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
/// `a[0].max(a[1]).max(a[2])` per lane (`max` returns the other operand on NaN, as
/// `f32::max` does).
#[inline(always)]
pub(super) fn max3<F: Lane>(a: F3<F>) -> F {
    a[0].max(a[1]).max(a[2])
}
/// `m ? a : b` per lane.
#[inline(always)]
pub(super) fn sel3<F: Lane>(m: F, a: F3<F>, b: F3<F>) -> F3<F> {
    [
        m.select(a[0], b[0]),
        m.select(a[1], b[1]),
        m.select(a[2], b[2]),
    ]
}
/// `x` in every lane.
#[inline(always)]
pub(super) fn splat<F: Lane>(x: f32) -> F {
    F::splat(x)
}
/// The lanes where `m` is set, as the low eight bits.
#[inline(always)]
pub(super) fn bits<F: Lane>(m: F) -> u32 {
    m.to_bitmask()
}
/// `RenderScene::offset` per lane.
#[inline(always)]
pub(super) fn offset4<F: Lane>(eps: f32, p: F3<F>, n: F3<F>) -> F3<F> {
    let m = p[0].abs().max(p[1].abs()).max(p[2].abs());
    add3(p, scale3(n, splat::<F>(eps) + splat::<F>(OFFSET_REL) * m))
}

/// `sampling::power_heuristic` per lane.
#[inline(always)]
pub(super) fn power4<F: Lane>(pa: F, pb: F) -> F {
    let a = pa * pa;
    let b = pb * pb;
    let s = a + b;
    let first = s.simd_gt(splat::<F>(0.0)) & a.is_finite();
    first.select(a / s, a.is_inf().select(splat::<F>(1.0), splat::<F>(0.0)))
}

/// `sampling::sin_cos_quarter` per lane (the same series, the same operation order).
#[inline(always)]
pub(super) fn sin_cos_quarter4<F: Lane>(a: F) -> (F, F) {
    let one = splat::<F>(1.0);
    let a2 = a * a;
    let r = SERIES_RECIPROCALS.map(splat::<F>);
    let s = a * (one - a2 * r[0] * (one - a2 * r[1] * (one - a2 * r[2])));
    let c = one - a2 * splat::<F>(0.5) * (one - a2 * r[3] * (one - a2 * r[4] * (one - a2 * r[5])));
    (s, c)
}

/// `sampling::cosine_hemisphere` per lane: the orthonormal basis of Duff et al. 2017 and
/// Malley's method over the concentric map, both branches computed and selected.
#[inline(always)]
pub(super) fn cosine_hemisphere4<F: Lane>(n: F3<F>, u: [F; 2]) -> F3<F> {
    let one = splat::<F>(1.0);
    let sign = n[2].is_sign_negative().select(splat::<F>(-1.0), one);
    let a = splat::<F>(-1.0) / (sign + n[2]);
    let b = n[0] * n[1] * a;
    let t = [one + sign * n[0] * n[0] * a, sign * b, -sign * n[0]];
    let bt = [b, sign + n[1] * n[1] * a, -n[1]];
    let two = splat::<F>(2.0);
    let ox = two * u[0] - one;
    let oy = two * u[1] - one;
    let zero = splat::<F>(0.0);
    let origin = ox.simd_eq(zero) & oy.simd_eq(zero);
    // Each lane evaluates the series once, at its own branch's angle.
    let wide_x = ox.abs().simd_gt(oy.abs());
    let ratio = wide_x.select(oy, ox) / wide_x.select(ox, oy);
    let (sn, cs) = sin_cos_quarter4(splat::<F>(FRAC_PI_4) * ratio);
    let x = wide_x.select(ox * cs, oy * sn);
    let y = wide_x.select(ox * sn, oy * cs);
    let x = origin.select(zero, x);
    let y = origin.select(zero, y);
    let z = (one - x * x - y * y).max(zero).sqrt();
    add3(add3(scale3(t, x), scale3(bt, y)), scale3(n, z))
}

/// A lane row as a register.
#[inline(always)]
pub(super) fn f4<F: Lane>(a: &[f32; L]) -> F {
    F::from_array(*a)
}
/// A `[axis][lane]` vector as registers.
#[inline(always)]
pub(super) fn f43<F: Lane>(a: &[[f32; L]; 3]) -> F3<F> {
    [f4(&a[0]), f4(&a[1]), f4(&a[2])]
}
/// Registers back into a `[axis][lane]` vector.
#[inline(always)]
pub(super) fn store3<F: Lane>(a: &mut [[f32; L]; 3], v: F3<F>) {
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
