//! `lane_math::Lane` on one 256-bit AVX register, for the x86-64-v3 build of the lane
//! loop's shading (`path_lanes::trace_avx2`): each operation is the instruction `wide`'s
//! SSE form of it uses, on eight lanes at once, so a lane's bits are the same.
//!
//! The methods are `#[inline(always)]` and not themselves built for AVX: their intrinsics
//! become instructions only once inlined into a caller built with AVX2, as the lane loop's
//! x86-64-v3 build is (elsewhere they would be calls). An `Avx8` exists only where `Avx8::new`
//! or the operations made it, and the lane loop makes one only after `bvh::Avx::detect_v3`.
#![cfg(target_arch = "x86_64")]

use super::lane_math::{Lane, L};
use std::arch::x86_64::*;
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

/// Eight floats in a `ymm` register.
#[derive(Clone, Copy, Debug)]
pub(super) struct Avx8(__m256);

macro_rules! binop {
    ($tr:ident, $f:ident, $op:ident) => {
        impl $tr for Avx8 {
            type Output = Avx8;
            #[inline(always)]
            fn $f(self, rhs: Avx8) -> Avx8 {
                // SAFETY: an `Avx8` exists only in the lane loop's AVX2 build.
                Avx8(unsafe { $op(self.0, rhs.0) })
            }
        }
    };
}
binop!(Add, add, _mm256_add_ps);
binop!(Sub, sub, _mm256_sub_ps);
binop!(Mul, mul, _mm256_mul_ps);
binop!(Div, div, _mm256_div_ps);
binop!(BitAnd, bitand, _mm256_and_ps);
binop!(BitOr, bitor, _mm256_or_ps);

impl Not for Avx8 {
    type Output = Avx8;
    #[inline(always)]
    fn not(self) -> Avx8 {
        // SAFETY: as for the binary operations.
        Avx8(unsafe { _mm256_xor_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(-1))) })
    }
}

impl Neg for Avx8 {
    type Output = Avx8;
    #[inline(always)]
    fn neg(self) -> Avx8 {
        // The sign bit flipped, as `wide` negates.
        // SAFETY: as for the binary operations.
        Avx8(unsafe { _mm256_xor_ps(self.0, _mm256_set1_ps(-0.0)) })
    }
}

/// The bits of `a` as eight integers compared for equality with `k` (all ones where equal).
#[inline(always)]
unsafe fn bits_eq(a: __m256i, k: i32) -> __m256 {
    _mm256_castsi256_ps(_mm256_cmpeq_epi32(a, _mm256_set1_epi32(k)))
}

/// A `Lane` comparison as `vcmpps` with predicate `$p`.
macro_rules! cmp {
    ($f:ident, $p:ident) => {
        #[inline(always)]
        fn $f(self, rhs: Self) -> Self {
            // SAFETY: an `Avx8` exists only in the lane loop's AVX2 build.
            Avx8(unsafe { _mm256_cmp_ps::<$p>(self.0, rhs.0) })
        }
    };
}

impl Lane for Avx8 {
    #[inline(always)]
    fn splat(x: f32) -> Self {
        // SAFETY (every method): an `Avx8` exists only in the lane loop's AVX2 build.
        Avx8(unsafe { _mm256_set1_ps(x) })
    }
    #[inline(always)]
    fn from_array(a: [f32; L]) -> Self {
        Avx8(unsafe { _mm256_loadu_ps(a.as_ptr()) })
    }
    #[inline(always)]
    fn to_array(self) -> [f32; L] {
        let mut a = [0.0f32; L];
        unsafe { _mm256_storeu_ps(a.as_mut_ptr(), self.0) };
        a
    }
    #[inline(always)]
    fn select(self, t: Self, f: Self) -> Self {
        // `blendvps`, as `wide` selects: the sign bit of each mask lane picks `t`.
        Avx8(unsafe { _mm256_blendv_ps(f.0, t.0, self.0) })
    }
    // The predicates of `wide`'s `cmpps` forms (ordered, but not-equal unordered).
    cmp!(simd_eq, _CMP_EQ_OQ);
    cmp!(simd_ne, _CMP_NEQ_UQ);
    cmp!(simd_lt, _CMP_LT_OQ);
    cmp!(simd_le, _CMP_LE_OQ);
    cmp!(simd_gt, _CMP_GT_OQ);
    #[inline(always)]
    fn max(self, rhs: Self) -> Self {
        // `maxps` returns its second operand when either is NaN; `wide` then keeps `self`
        // where `rhs` is NaN, as `f32::max` does.
        unsafe {
            let m = _mm256_max_ps(self.0, rhs.0);
            let nan = _mm256_cmp_ps::<_CMP_UNORD_Q>(rhs.0, rhs.0);
            Avx8(_mm256_blendv_ps(m, self.0, nan))
        }
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Avx8(unsafe { _mm256_and_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(i32::MAX))) })
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Avx8(unsafe { _mm256_sqrt_ps(self.0) })
    }
    #[inline(always)]
    fn is_finite(self) -> Self {
        // Exponent not all ones, as `wide`'s shift-and-compare.
        unsafe {
            let u = _mm256_slli_epi32::<1>(_mm256_castps_si256(self.0));
            let e = _mm256_and_si256(u, _mm256_set1_epi32(0xFF00_0000u32 as i32));
            !Avx8(bits_eq(e, 0xFF00_0000u32 as i32))
        }
    }
    #[inline(always)]
    fn is_inf(self) -> Self {
        unsafe {
            let u = _mm256_slli_epi32::<1>(_mm256_castps_si256(self.0));
            Avx8(bits_eq(u, 0xFF00_0000u32 as i32))
        }
    }
    #[inline(always)]
    fn is_sign_negative(self) -> Self {
        unsafe {
            let sign = _mm256_and_si256(_mm256_castps_si256(self.0), _mm256_set1_epi32(i32::MIN));
            Avx8(bits_eq(sign, i32::MIN))
        }
    }
    #[inline(always)]
    fn to_bitmask(self) -> u32 {
        unsafe { _mm256_movemask_ps(self.0) as u32 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use wide::f32x8;

    /// Every operation gives `wide`'s bits, on values where the instructions could differ:
    /// signed zeros, subnormals, infinities, NaNs of either sign, the largest finite float.
    #[test]
    fn avx_lanes_are_the_sse_ones() {
        if crate::bvh::Avx::detect_v3().is_none() {
            assert!(
                std::env::var("CI").is_err(),
                "CI runs on CPUs with x86-64-v3"
            );
            return;
        }
        let special = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            1e-40,
            -1e-40,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            f32::MAX,
            1e-8,
            7.25,
            -2.5,
            0.1,
        ];
        let bits = |a: [f32; L]| a.map(f32::to_bits);
        for i in 0..special.len() {
            let a: [f32; L] = std::array::from_fn(|k| special[(i + k) % special.len()]);
            for j in 0..special.len() {
                let b: [f32; L] = std::array::from_fn(|k| special[(j + 3 * k) % special.len()]);
                let (x, y) = (Avx8::from_array(a), Avx8::from_array(b));
                let (p, q) = (f32x8::from_array(a), f32x8::from_array(b));
                let pairs: [(Avx8, f32x8, &str); 19] = [
                    (x + y, p + q, "add"),
                    (x - y, p - q, "sub"),
                    (x * y, p * q, "mul"),
                    (x / y, p / q, "div"),
                    (x & y, p & q, "and"),
                    (x | y, p | q, "or"),
                    (!x, !p, "not"),
                    (-x, -p, "neg"),
                    (x.simd_eq(y), Lane::simd_eq(p, q), "eq"),
                    (x.simd_ne(y), Lane::simd_ne(p, q), "ne"),
                    (x.simd_lt(y), Lane::simd_lt(p, q), "lt"),
                    (x.simd_le(y), Lane::simd_le(p, q), "le"),
                    (x.simd_gt(y), Lane::simd_gt(p, q), "gt"),
                    (Lane::max(x, y), Lane::max(p, q), "max"),
                    (Lane::abs(x), Lane::abs(p), "abs"),
                    (Lane::sqrt(x), Lane::sqrt(p), "sqrt"),
                    (Lane::is_finite(x), Lane::is_finite(p), "is_finite"),
                    (Lane::is_inf(x), Lane::is_inf(p), "is_inf"),
                    (Lane::is_sign_negative(x), Lane::is_sign_negative(p), "sign"),
                ];
                for (v, w, what) in pairs {
                    assert_eq!(
                        bits(v.to_array()),
                        bits(Lane::to_array(w)),
                        "{what} {a:?} {b:?}"
                    );
                }
                let (m, n) = (x.simd_lt(y), Lane::simd_lt(p, q));
                let (s, t) = (m.select(x, y), Lane::select(n, p, q));
                assert_eq!(bits(s.to_array()), bits(Lane::to_array(t)), "select");
                assert_eq!(m.to_bitmask(), Lane::to_bitmask(n), "bitmask");
            }
        }
    }
}
