//! Lane building blocks of the 8-wide BVH: `[f32; 4]` helpers computed as packed SSE
//! through the `wide` crate (safe code; `minps`, `maxps`, and comparisons straight to a bit
//! mask with `cmpps` + `movmskps`, which LLVM had turned into four `ucomiss` and `set`s per
//! mask when they were written as plain lane-wise Rust: docs/path_tracing.md, "How it runs");
//! the eight-box slab test, on two SSE halves (`Sse`) or one AVX register (`Avx`, the same
//! bits); and the watertight ray-triangle test of Woop, Benthin and Wald 2013 run on four
//! triangles stored axis by axis (`Tri4`).
//!
//! Every lane computes exactly the operations of the scalar `tri_test`, in the same order
//! (Rust never contracts to FMA), so a lane's result is bit for bit the scalar one; the
//! rare lanes that need the scalar test's double-precision fallback are handed to it.

use super::traverse::{intersect_triangle, tri_test, RayPre};
use crate::sampling::V3;
use wide::{f32x4, f32x8};

/// The axis permutation of the watertight test (`RayPre`'s kx, ky, kz): fixed at compile
/// time (`Fixed`, constant indices into a `Tri4`) for the single-ray traversal, which is
/// monomorphised per permutation, or read from the ray (`Dyn`) for the interleaved
/// traversal of two rays, which would need 36 instances otherwise.
pub trait Axes: Copy {
    /// (kx, ky, kz).
    fn get(self) -> (usize, usize, usize);
    /// The scalar watertight test with this permutation (for lanes on an edge).
    fn scalar(self, r: &RayPre, tri: &[V3; 3], tmax: f32) -> Option<(f32, f32, f32)>;
}

/// A permutation known at compile time.
#[derive(Clone, Copy, Debug)]
pub struct Fixed<const KX: usize, const KY: usize, const KZ: usize>;

impl<const KX: usize, const KY: usize, const KZ: usize> Axes for Fixed<KX, KY, KZ> {
    #[inline(always)]
    fn get(self) -> (usize, usize, usize) {
        (KX, KY, KZ)
    }
    #[inline(always)]
    fn scalar(self, r: &RayPre, tri: &[V3; 3], tmax: f32) -> Option<(f32, f32, f32)> {
        tri_test::<KX, KY, KZ>(r, tri, tmax)
    }
}

/// A permutation read at run time.
#[derive(Clone, Copy, Debug)]
pub struct Dyn(pub usize, pub usize, pub usize);

impl Axes for Dyn {
    #[inline(always)]
    fn get(self) -> (usize, usize, usize) {
        (self.0, self.1, self.2)
    }
    #[inline(never)]
    fn scalar(self, r: &RayPre, tri: &[V3; 3], tmax: f32) -> Option<(f32, f32, f32)> {
        intersect_triangle(r, tri, tmax)
    }
}

/// Four floats, one per lane.
pub type F4 = [f32; 4];

/// The lanes as an SSE register (`wide`, already a dependency through nalgebra's simba):
/// its packed operations and comparisons are safe code, and `to_bitmask` is `movmskps`.
#[inline(always)]
fn w(a: F4) -> f32x4 {
    f32x4::new(a)
}

#[inline(always)]
fn sub4(a: F4, b: F4) -> F4 {
    (w(a) - w(b)).to_array()
}

#[inline(always)]
fn mul4(a: F4, b: F4) -> F4 {
    (w(a) * w(b)).to_array()
}

#[inline(always)]
fn add4(a: F4, b: F4) -> F4 {
    (w(a) + w(b)).to_array()
}

/// A lane comparison; every one is false on NaN, as the scalar comparison is.
#[derive(Clone, Copy, Debug)]
enum Cmp {
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
}

/// The lanes where `a op b` holds, as the low four bits (`cmpps` + `movmskps`; `op` is a
/// constant at every call, so the match folds away).
#[inline(always)]
fn mask(a: F4, op: Cmp, b: F4) -> u32 {
    let (a, b) = (w(a), w(b));
    let m = match op {
        Cmp::Lt => a.simd_lt(b),
        Cmp::Le => a.simd_le(b),
        Cmp::Gt => a.simd_gt(b),
        Cmp::Ge => a.simd_ge(b),
        Cmp::Eq => a.simd_eq(b),
    };
    m.to_bitmask()
}

/// Eight floats, one per child box of a node.
pub type F8 = [f32; 8];

/// A ray for the box test: origin and inverse direction per axis, broadcast to the lanes
/// where they are used, and per axis whether the direction is negative (then the near slab
/// is the box's max).
#[derive(Clone, Copy, Debug)]
pub struct RayBox {
    org: V3,
    inv: V3,
    neg: [bool; 3],
}

impl RayBox {
    /// The box-test form of the ray of `r`.
    #[inline(always)]
    pub fn new(r: &RayPre) -> RayBox {
        RayBox {
            org: r.org,
            inv: r.inv,
            neg: [r.inv[0] < 0.0, r.inv[1] < 0.0, r.inv[2] < 0.0],
        }
    }
}

/// Slab test of one ray against eight boxes (`min[axis][lane]`, `max[axis][lane]`) on
/// eight lanes (`wide::f32x8`, which this crate's builds compute as two SSE halves: `wide`
/// picks its AVX form only when the whole crate is built for AVX; `Avx` is the 256-bit
/// form for the lane loop's x86-64-v3 build): the mask of the boxes entered before
/// `tmax` and the entry distances. A NaN from `0 * inf` keeps the previous bound (`maxps`
/// and `minps` return their second operand then), and the exit distance is widened by
/// 1 + 2 gamma(3) so round-off cannot cull a hit on a face (Ize 2013, "Robust BVH Ray
/// Traversal"), as in the binary traversal. An empty lane (min = +inf, max = -inf) is
/// never entered.
#[inline(always)]
pub fn slab8(r: &RayBox, min: &[F8; 3], max: &[F8; 3], tmax: f32) -> (u32, F8) {
    let mut t0 = f32x8::splat(0.0);
    let mut t1 = f32x8::splat(tmax);
    for k in 0..3 {
        let (near, far) = if r.neg[k] {
            (max[k], min[k])
        } else {
            (min[k], max[k])
        };
        let o = f32x8::splat(r.org[k]);
        let inv = f32x8::splat(r.inv[k]);
        t0 = ((f32x8::new(near) - o) * inv).fast_max(t0);
        t1 = ((f32x8::new(far) - o) * inv).fast_min(t1);
    }
    let t1 = t1 * f32x8::splat(1.000_000_4);
    (t0.simd_le(t1).to_bitmask(), t0.to_array())
}

/// How a node's eight boxes are tested: `Sse`, `slab8` on two SSE halves (every x86-64
/// CPU), or `Avx`, the same operations on one 256-bit register (half the instructions, the
/// same bits). The traversal is generic over it, so the lane loop's x86-64-v3 build
/// takes `Avx` and everything else `Sse`.
pub trait Slab: Copy {
    /// Whether the loops built with this test walk the tree inline (`Bvh::closest_in`): the
    /// x86-64-v3 builds, where a call would pass the AVX registers through memory; the
    /// baseline calls the walks specialised per axis permutation.
    const INLINE_WALKS: bool;

    /// `slab8`'s answer.
    fn slab8(self, r: &RayBox, min: &[F8; 3], max: &[F8; 3], tmax: f32) -> (u32, F8);
}

/// `slab8` as it is: two SSE halves through `wide`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Sse;

impl Slab for Sse {
    const INLINE_WALKS: bool = false;

    #[inline(always)]
    fn slab8(self, r: &RayBox, min: &[F8; 3], max: &[F8; 3], tmax: f32) -> (u32, F8) {
        slab8(r, min, max, tmax)
    }
}

/// `slab8` on AVX's 256-bit registers; a value exists only on a CPU with AVX (`detect`).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub struct Avx(());

#[cfg(target_arch = "x86_64")]
impl Avx {
    /// An `Avx` when this CPU has AVX.
    pub fn detect() -> Option<Avx> {
        std::is_x86_feature_detected!("avx").then_some(Avx(()))
    }

    /// An `Avx` when this CPU has all of x86-64-v3 that the tracers' second builds are
    /// compiled for (AVX2, FMA, BMI1/2, LZCNT, POPCNT).
    pub fn detect_v3() -> Option<Avx> {
        let v3 = std::is_x86_feature_detected!("avx2")
            && std::is_x86_feature_detected!("fma")
            && std::is_x86_feature_detected!("bmi1")
            && std::is_x86_feature_detected!("bmi2")
            && std::is_x86_feature_detected!("lzcnt")
            && std::is_x86_feature_detected!("popcnt");
        if v3 {
            Avx::detect()
        } else {
            None
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl Slab for Avx {
    const INLINE_WALKS: bool = true;

    #[inline(always)]
    fn slab8(self, r: &RayBox, min: &[F8; 3], max: &[F8; 3], tmax: f32) -> (u32, F8) {
        // SAFETY: an `Avx` is made only by `Avx::detect`, on a CPU that has AVX.
        unsafe { slab8_avx(r, min, max, tmax) }
    }
}

/// `slab8`'s operations in the same order on `ymm` registers: `vsubps`, `vmulps`,
/// `vmaxps`/`vminps` with the previous bound as second operand (kept on NaN, as `maxps`
/// keeps it), `vcmpps` less-or-equal ordered (false on NaN, as `cmpleps`) and `vmovmskps`.
/// Unsafe: the CPU must have AVX. Not itself marked `target_feature` (that would forbid
/// inlining it always): the intrinsics inline where the caller is built with AVX, as
/// `path_lanes::trace_avx2` is, and would be calls elsewhere.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn slab8_avx(r: &RayBox, min: &[F8; 3], max: &[F8; 3], tmax: f32) -> (u32, F8) {
    use std::arch::x86_64::*;
    let mut t0 = _mm256_setzero_ps();
    let mut t1 = _mm256_set1_ps(tmax);
    for k in 0..3 {
        let (near, far) = if r.neg[k] {
            (&max[k], &min[k])
        } else {
            (&min[k], &max[k])
        };
        let o = _mm256_set1_ps(r.org[k]);
        let inv = _mm256_set1_ps(r.inv[k]);
        let tn = _mm256_mul_ps(_mm256_sub_ps(_mm256_loadu_ps(near.as_ptr()), o), inv);
        let tf = _mm256_mul_ps(_mm256_sub_ps(_mm256_loadu_ps(far.as_ptr()), o), inv);
        t0 = _mm256_max_ps(tn, t0);
        t1 = _mm256_min_ps(tf, t1);
    }
    let t1 = _mm256_mul_ps(t1, _mm256_set1_ps(1.000_000_4));
    let m = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1)) as u32;
    let mut te = [0.0f32; 8];
    _mm256_storeu_ps(te.as_mut_ptr(), t0);
    (m, te)
}

/// Up to four triangles of a leaf, axis by axis: `v[corner][axis][lane]`, and the
/// caller's index of each. Unused lanes repeat lane 0 (finite values, never reported).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct Tri4 {
    /// Corners per axis per lane.
    pub v: [[F4; 3]; 3],
    /// Caller's triangle index per lane.
    pub prim: [u32; 4],
}

impl Tri4 {
    /// Packs `tris` (1 to 4 triangles) and their caller indices `prim`.
    pub fn pack(tris: &[[V3; 3]], prim: &[u32]) -> Tri4 {
        let mut q = Tri4 {
            v: [[[0.0; 4]; 3]; 3],
            prim: [prim[0]; 4],
        };
        for l in 0..4 {
            let i = if l < tris.len() { l } else { 0 };
            q.prim[l] = prim[i];
            for (c, p) in tris[i].iter().enumerate() {
                for (k, x) in p.iter().enumerate() {
                    q.v[c][k][l] = *x;
                }
            }
        }
        q
    }

    /// The triangle of lane `l` as corners.
    #[inline]
    pub fn get(&self, l: usize) -> [V3; 3] {
        let c = |c: usize| [self.v[c][0][l], self.v[c][1][l], self.v[c][2][l]];
        [c(0), c(1), c(2)]
    }
}

/// One corner of four triangles (`p[axis][lane]`) moved to the ray's frame: translated by
/// the permuted origin `o`, sheared and scaled by `sh` = (sx, sy, sz) (Woop et al. 2013,
/// eq. 5). A plain function, not a closure: LLVM would not inline the closure once the
/// permutation is a run-time value (`Dyn`).
#[inline(always)]
fn shear(p: &[F4; 3], k: (usize, usize, usize), o: V3, sh: V3) -> (F4, F4, F4) {
    let dx = sub4(p[k.0], [o[0]; 4]);
    let dy = sub4(p[k.1], [o[1]; 4]);
    let dz = sub4(p[k.2], [o[2]; 4]);
    (
        sub4(dx, mul4([sh[0]; 4], dz)),
        sub4(dy, mul4([sh[1]; 4], dz)),
        mul4([sh[2]; 4], dz),
    )
}

/// The watertight test (Woop et al. 2013, Listing 1) of one ray against the first `count`
/// triangles of `q`, visited in lane order exactly as the scalar loop over a leaf does:
/// a lane hit before the current `tmax` lowers it for the lanes after it. Calls `hit(t,
/// u, v, lane)` for every accepted hit; with `ANY`, stops at the first and returns true.
#[inline(always)]
pub fn tri4<const ANY: bool, P: Axes>(
    r: &RayPre,
    axes: P,
    q: &Tri4,
    count: usize,
    tmax: &mut f32,
    mut hit: impl FnMut(f32, f32, f32, usize),
) -> bool {
    let z = [0.0f32; 4];
    let (kx, ky, kz) = axes.get();
    // Translate to the origin, shear and scale (eq. 5), per corner, on four lanes.
    let o = [r.org[kx], r.org[ky], r.org[kz]];
    let sh = [r.sx, r.sy, r.sz];
    let (ax, ay, az) = shear(&q.v[0], (kx, ky, kz), o, sh);
    let (bx, by, bz) = shear(&q.v[1], (kx, ky, kz), o, sh);
    let (cx, cy, cz) = shear(&q.v[2], (kx, ky, kz), o, sh);
    // Scaled barycentrics (2-D edge functions).
    let u = sub4(mul4(cx, by), mul4(cy, bx));
    let v = sub4(mul4(ax, cy), mul4(ay, cx));
    let w = sub4(mul4(bx, ay), mul4(by, ax));
    let live = (1u32 << count) - 1;
    let eq = |a: F4| mask(a, Cmp::Eq, z);
    let lt = |a: F4| mask(a, Cmp::Lt, z);
    let gt = |a: F4| mask(a, Cmp::Gt, z);
    // Lanes on an edge go to the scalar test's double-precision fallback (section 3.3).
    let edge = (eq(u) | eq(v) | eq(w)) & live;
    let outside = (lt(u) | lt(v) | lt(w)) & (gt(u) | gt(v) | gt(w));
    // Most leaf tests miss every triangle: stop before the depth test then.
    if (live & !outside) | edge == 0 {
        return false;
    }
    let det = add4(add4(u, v), w);
    let t = add4(add4(mul4(u, az), mul4(v, bz)), mul4(w, cz));
    // The sign-aware depth test of section 3.4 against the current `tmax`: a lane failing
    // it here fails it for every smaller `tmax` too, so only the rest are looked at again.
    let td = mul4([*tmax; 4], det);
    let pos = gt(det);
    let reject_pos = mask(t, Cmp::Le, z) | mask(t, Cmp::Ge, td);
    let reject_neg = mask(t, Cmp::Ge, z) | mask(t, Cmp::Le, td);
    let depth = (pos & !reject_pos) | (!pos & !reject_neg);
    let mut cand = (live & !edge & !outside & !eq(det) & depth) | edge;
    while cand != 0 {
        let l = cand.trailing_zeros() as usize;
        cand &= cand - 1;
        let found = if edge & (1 << l) != 0 {
            axes.scalar(r, &q.get(l), *tmax)
        } else {
            let (t, det) = (t[l], det[l]);
            let rejected = if det > 0.0 {
                t <= 0.0 || t >= *tmax * det
            } else {
                t >= 0.0 || t <= *tmax * det
            };
            if rejected {
                None
            } else {
                let rcp = 1.0 / det;
                Some((t * rcp, v[l] * rcp, w[l] * rcp))
            }
        };
        if let Some((th, b1, b2)) = found {
            *tmax = th;
            hit(th, b1, b2, l);
            if ANY {
                return true;
            }
        }
    }
    false
}
