//! BVH traversal: front-to-back closest-hit and any-hit queries with the watertight
//! ray-triangle test of Woop, Benthin and Wald 2013 and a conservative slab test.

use super::{Aabb, Bvh, Hit};
use crate::sampling::{sub, V3};
use std::cell::RefCell;
use wide::f32x4;

/// Entries of a traversal stack: (node, entry distance). An 8-wide node adds at most seven
/// pending entries per level and a binary node one, so 256 entries hold 36 levels of
/// 8-wide nodes entered on every lane; trees over millions of triangles stay far below
/// that (a full stack drops entries rather than overflow).
pub(super) const STACK: usize = 256;

thread_local! {
    /// One traversal stack per thread, reused by every ray: a stack array local to the
    /// traversal was zeroed (a 768-byte `memset`) on every ray, 2.7 % of the path tracer's
    /// time (docs/path_tracing.md).
    /// Two stacks, for the interleaved traversal of two rays (`Bvh::intersect_occluded`).
    static STACKS: RefCell<[(u32, f32); 2 * STACK]> =
        const { RefCell::new([(0, 0.0); 2 * STACK]) };
}

/// Runs `f` with this thread's traversal stack (a fresh one if it is already in use).
#[inline(always)]
pub(super) fn with_stack<R>(f: impl FnOnce(&mut [(u32, f32)]) -> R) -> R {
    STACKS.with(|s| match s.try_borrow_mut() {
        Ok(mut s) => f(&mut s[..STACK]),
        Err(_) => f(&mut [(0, 0.0); STACK]),
    })
}

/// A traversal stack: (node, entry distance) entries.
pub(super) type Stack = [(u32, f32)];

/// Runs `f` with this thread's two traversal stacks (fresh ones if they are in use).
#[inline(always)]
pub(super) fn with_stacks<R>(f: impl FnOnce(&mut [(u32, f32)], &mut [(u32, f32)]) -> R) -> R {
    STACKS.with(|s| match s.try_borrow_mut() {
        Ok(mut s) => {
            let (a, b) = s.split_at_mut(STACK);
            f(a, b)
        }
        Err(_) => f(&mut [(0, 0.0); STACK], &mut [(0, 0.0); STACK]),
    })
}

/// Per-ray constants of the watertight test (Woop et al. 2013, section 3): the dominant
/// axis `kz`, the permuted axes and the shear that maps the ray to +z.
#[derive(Clone, Copy, Debug)]
pub struct RayPre {
    pub(super) org: V3,
    pub(super) inv: V3,
    pub(super) kx: usize,
    pub(super) ky: usize,
    pub(super) kz: usize,
    pub(super) sx: f32,
    pub(super) sy: f32,
    pub(super) sz: f32,
}

impl RayPre {
    /// The axis permutation (kx, ky, kz) of the watertight test: `kz` the dominant axis.
    #[inline(always)]
    pub fn axes(&self) -> (usize, usize, usize) {
        (self.kx, self.ky, self.kz)
    }

    /// Precomputes the ray `org + t dir`.
    #[inline]
    pub fn new(org: V3, dir: V3) -> RayPre {
        // The magnitudes on one register from the direction as it is stored (a pair load
        // of `dir[1..3]`, which LLVM made otherwise, straddles the two stores that wrote
        // the direction and stalls until both retire).
        let a = f32x4::new([dir[0], dir[1], dir[2], 0.0]).abs().to_array();
        let kz = if a[0] > a[1] {
            if a[0] > a[2] {
                0
            } else {
                2
            }
        } else if a[1] > a[2] {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Swap to preserve the winding of the triangle.
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        // One packed division for the three reciprocals; the shear takes the dominant
        // axis' reciprocal instead of dividing again (docs/path_tracing.md, twelfth
        // round).
        let inv = (f32x4::splat(1.0) / f32x4::new([dir[0], dir[1], dir[2], 1.0])).to_array();
        let sz = inv[kz];
        RayPre {
            org,
            inv: [inv[0], inv[1], inv[2]],
            kx,
            ky,
            kz,
            sx: dir[kx] * sz,
            sy: dir[ky] * sz,
            sz,
        }
    }
}

/// Watertight ray-triangle intersection (Woop et al. 2013, Listing 1). Returns
/// `(t, b1, b2)` with `0 < t < tmax`; edges shared by two triangles are never missed.
#[inline(always)]
pub fn intersect_triangle(r: &RayPre, tri: &[V3; 3], tmax: f32) -> Option<(f32, f32, f32)> {
    match (r.kx, r.ky, r.kz) {
        (1, 2, 0) => tri_test::<1, 2, 0>(r, tri, tmax),
        (2, 1, 0) => tri_test::<2, 1, 0>(r, tri, tmax),
        (2, 0, 1) => tri_test::<2, 0, 1>(r, tri, tmax),
        (0, 2, 1) => tri_test::<0, 2, 1>(r, tri, tmax),
        (0, 1, 2) => tri_test::<0, 1, 2>(r, tri, tmax),
        _ => tri_test::<1, 0, 2>(r, tri, tmax),
    }
}

/// `intersect_triangle` with the ray's axis permutation (`RayPre::axes`) fixed at compile
/// time (no indexed loads), for loops over many triangles; any other permutation gives
/// wrong answers, so callers match on `RayPre::axes` first.
#[inline(always)]
pub(crate) fn tri_test<const KX: usize, const KY: usize, const KZ: usize>(
    r: &RayPre,
    tri: &[V3; 3],
    tmax: f32,
) -> Option<(f32, f32, f32)> {
    let a = sub(tri[0], r.org);
    let b = sub(tri[1], r.org);
    let c = sub(tri[2], r.org);
    // Shear and scale the vertices (eq. 5).
    let ax = a[KX] - r.sx * a[KZ];
    let ay = a[KY] - r.sy * a[KZ];
    let bx = b[KX] - r.sx * b[KZ];
    let by = b[KY] - r.sy * b[KZ];
    let cx = c[KX] - r.sx * c[KZ];
    let cy = c[KY] - r.sy * c[KZ];
    sheared_test([ax, ay, bx, by, cx, cy], [a[KZ], b[KZ], c[KZ]], r.sz, tmax)
}

/// The watertight test's second half (Woop et al. 2013, sections 3.2-3.4) on a triangle
/// already sheared into the ray's frame: its corners' sheared `[ax, ay, bx, by, cx, cy]`,
/// their coordinates along the dominant axis `z` (relative to the origin) and the ray's
/// `sz`. Shared by `tri_test` and the camera grid's eight-ray test, which hands it the
/// rays whose edge functions need the double-precision fallback.
#[inline(always)]
pub(crate) fn sheared_test(
    [ax, ay, bx, by, cx, cy]: [f32; 6],
    z: [f32; 3],
    sz: f32,
    tmax: f32,
) -> Option<(f32, f32, f32)> {
    // Scaled barycentrics (2-D edge functions).
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;
    // Fall back to double precision on an edge (section 3.3).
    if u == 0.0 || v == 0.0 || w == 0.0 {
        let (ax, ay, bx, by, cx, cy) = (
            ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
        );
        u = (cx * by - cy * bx) as f32;
        v = (ax * cy - ay * cx) as f32;
        w = (bx * ay - by * ax) as f32;
    }
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 {
        return None;
    }
    let az = sz * z[0];
    let bz = sz * z[1];
    let cz = sz * z[2];
    let t = u * az + v * bz + w * cz;
    // Sign-aware depth test without dividing (section 3.4).
    if det > 0.0 {
        if t <= 0.0 || t >= tmax * det {
            return None;
        }
    } else if t >= 0.0 || t <= tmax * det {
        return None;
    }
    let rcp = 1.0 / det;
    Some((t * rcp, v * rcp, w * rcp))
}

/// Slab test; returns the entry distance when the box is hit before `tmax`.
#[inline(always)]
fn intersect_aabb(r: &RayPre, b: &Aabb, tmax: f32) -> Option<f32> {
    let mut t0 = 0.0f32;
    let mut t1 = tmax;
    for k in 0..3 {
        let ta = (b.min[k] - r.org[k]) * r.inv[k];
        let tb = (b.max[k] - r.org[k]) * r.inv[k];
        // Plain comparisons (minss/maxss): a NaN from 0 * inf keeps the previous bound.
        let (lo, hi) = if ta < tb { (ta, tb) } else { (tb, ta) };
        t0 = if lo > t0 { lo } else { t0 };
        t1 = if hi < t1 { hi } else { t1 };
    }
    // Widen slightly so round-off in the slab test cannot cull a hit on a box face
    // (Ize 2013, "Robust BVH Ray Traversal": multiply by 1 + 2 gamma(3)).
    if t0 <= t1 * 1.000_000_4 {
        Some(t0)
    } else {
        None
    }
}

impl Bvh {
    /// The closest hit of `org + t dir` with `0 < t < tmax`.
    #[inline]
    pub fn intersect(&self, org: V3, dir: V3, tmax: f32) -> Option<Hit> {
        self.traverse::<false>(org, dir, tmax)
    }

    /// Whether anything blocks `org + t dir` for `0 < t < tmax` (any-hit, for shadow rays).
    #[inline]
    pub fn occluded(&self, org: V3, dir: V3, tmax: f32) -> bool {
        self.traverse::<true>(org, dir, tmax).is_some()
    }

    #[inline]
    pub(super) fn traverse<const ANY: bool>(&self, org: V3, dir: V3, tmax: f32) -> Option<Hit> {
        if self.nodes.is_empty() {
            return None;
        }
        let r = RayPre::new(org, dir);
        if !self.wide.is_empty() {
            return match (r.kx, r.ky, r.kz) {
                (1, 2, 0) => self.traverse8::<ANY, 1, 2, 0>(&r, tmax),
                (2, 1, 0) => self.traverse8::<ANY, 2, 1, 0>(&r, tmax),
                (2, 0, 1) => self.traverse8::<ANY, 2, 0, 1>(&r, tmax),
                (0, 2, 1) => self.traverse8::<ANY, 0, 2, 1>(&r, tmax),
                (0, 1, 2) => self.traverse8::<ANY, 0, 1, 2>(&r, tmax),
                _ => self.traverse8::<ANY, 1, 0, 2>(&r, tmax),
            };
        }
        match (r.kx, r.ky, r.kz) {
            (1, 2, 0) => self.traverse_k::<ANY, 1, 2, 0>(&r, tmax),
            (2, 1, 0) => self.traverse_k::<ANY, 2, 1, 0>(&r, tmax),
            (2, 0, 1) => self.traverse_k::<ANY, 2, 0, 1>(&r, tmax),
            (0, 2, 1) => self.traverse_k::<ANY, 0, 2, 1>(&r, tmax),
            (0, 1, 2) => self.traverse_k::<ANY, 0, 1, 2>(&r, tmax),
            _ => self.traverse_k::<ANY, 1, 0, 2>(&r, tmax),
        }
    }

    fn traverse_k<const ANY: bool, const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        r: &RayPre,
        tmax: f32,
    ) -> Option<Hit> {
        with_stack(|stack| self.walk2::<ANY, KX, KY, KZ>(r, tmax, stack))
    }

    #[inline(always)]
    fn walk2<const ANY: bool, const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        r: &RayPre,
        tmax: f32,
        stack: &mut [(u32, f32)],
    ) -> Option<Hit> {
        let r = *r;
        let mut best: Option<Hit> = None;
        let mut tmax = tmax;
        // Stack of (node, entry distance): a popped node is skipped once a closer hit has
        // been found than its entry distance.
        let mut sp = 0usize;
        let mut node = 0usize;
        intersect_aabb(&r, &self.nodes[0].bounds, tmax)?;
        'outer: loop {
            let n = &self.nodes[node];
            if n.count > 0 {
                let s = n.first as usize;
                for i in s..s + n.count as usize {
                    if let Some((t, u, v)) = tri_test::<KX, KY, KZ>(&r, &self.tris[i], tmax) {
                        tmax = t;
                        best = Some(Hit {
                            t,
                            prim: self.prim[i],
                            u,
                            v,
                        });
                        if ANY {
                            return best;
                        }
                    }
                }
            } else {
                let a = n.first as usize;
                let ta = intersect_aabb(&r, &self.nodes[a].bounds, tmax);
                let tb = intersect_aabb(&r, &self.nodes[a + 1].bounds, tmax);
                match (ta, tb) {
                    (Some(x), Some(y)) => {
                        let (near, far, tfar) = if x <= y { (a, a + 1, y) } else { (a + 1, a, x) };
                        if sp < stack.len() {
                            stack[sp] = (far as u32, tfar);
                            sp += 1;
                        }
                        node = near;
                        continue;
                    }
                    (Some(_), None) => {
                        node = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = a + 1;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            while sp > 0 {
                sp -= 1;
                let (n, t) = stack[sp];
                if t <= tmax {
                    node = n as usize;
                    continue 'outer;
                }
            }
            break;
        }
        best
    }
}
