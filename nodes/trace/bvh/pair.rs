//! Two independent rays traced in one interleaved loop: one node (or leaf) step of the
//! first, then one of the second, and so on. A single ray's walk down the 8-wide tree is a
//! dependent chain (load a node, slab test, mask, child index, load the next node), so a
//! core running one ray waits on that chain's latency; the other ray's step has no data
//! dependence on it, and the out-of-order core overlaps the two (software pipelining of
//! independent chains, the motivation of ray streams: Wald et al. 2014, "Embree: A Kernel
//! Framework for Efficient CPU Ray Tracing", section 4; docs/path_tracing.md, fourth
//! round, has the measurements). Each ray gets its own stack and exactly the node order,
//! hits and `tmax` updates of a single-ray query, so the answers are bit for bit those of
//! `intersect` and `occluded`.

use super::lanes::{Dyn, Slab, Sse};
use super::traverse::{with_stacks, RayPre, Stack, STACK};
use super::wide::Walk;
use super::{Bvh, Hit};
use crate::sampling::V3;

/// A ray segment to trace: origin, direction, and the far end of the ray parameter
/// (hits count for `0 < t < tmax`).
pub type Segment = (V3, V3, f32);

/// Two traversal stacks owned by the caller, for a loop that traces many pairs of rays
/// (`Bvh::intersect_occluded_in`): it takes them once instead of the thread's own stacks
/// (a thread-local look-up and a borrow) per query. They also carry the node box test
/// (`Slab`) that the queries on them use.
pub struct TraceStacks<S: Slab = Sse> {
    a: [(u32, f32); STACK],
    b: [(u32, f32); STACK],
    slab: S,
}

impl TraceStacks {
    /// Fresh stacks (4 KiB, zeroed once), testing node boxes on SSE.
    pub fn new() -> TraceStacks {
        TraceStacks::with_slab(Sse)
    }
}

impl<S: Slab> TraceStacks<S> {
    /// Fresh stacks whose queries test node boxes with `slab`.
    pub fn with_slab(slab: S) -> TraceStacks<S> {
        TraceStacks {
            a: [(0, 0.0); STACK],
            b: [(0, 0.0); STACK],
            slab,
        }
    }

    /// The two stacks, apart, and the box test.
    #[inline(always)]
    pub(super) fn split(&mut self) -> (&mut Stack, &mut Stack, S) {
        (&mut self.a, &mut self.b, self.slab)
    }
}

impl Default for TraceStacks {
    fn default() -> Self {
        TraceStacks::new()
    }
}

impl Bvh {
    /// The closest hit along `a` and whether anything blocks `b` (an any-hit query), the
    /// two traced interleaved: the same answers as `intersect(a)` and `occluded(b)`.
    #[inline]
    pub fn intersect_occluded(&self, a: Segment, b: Segment) -> (Option<Hit>, bool) {
        with_stacks(|sa, sb| {
            let (ha, hb) = self.trace_pair::<false, true, _>(a, b, sa, sb, Sse);
            (ha, hb.is_some())
        })
    }

    /// `intersect_occluded` on the caller's stacks, for a loop that traces many pairs.
    #[inline(always)]
    pub fn intersect_occluded_in<S: Slab>(
        &self,
        st: &mut TraceStacks<S>,
        a: Segment,
        b: Segment,
    ) -> (Option<Hit>, bool) {
        let (sa, sb, slab) = st.split();
        let (ha, hb) = self.trace_pair::<false, true, _>(a, b, sa, sb, slab);
        (ha, hb.is_some())
    }

    /// The closest hit along `a` (or, with `ANY`, whether anything blocks it: `Some` then)
    /// on the caller's stack, walked inline with the axis permutation read from the ray:
    /// the same answer as `intersect` (`occluded`), in the caller's build (the lane
    /// loop's x86-64-v3 one) instead of the baseline build's `traverse`.
    #[inline(always)]
    pub fn single_in<const ANY: bool, S: Slab>(
        &self,
        st: &mut TraceStacks<S>,
        a: Segment,
    ) -> Option<Hit> {
        if self.wide.is_empty() {
            return self.traverse::<ANY>(a.0, a.1, a.2);
        }
        let r = RayPre::new(a.0, a.1);
        let p = Dyn(r.kx, r.ky, r.kz);
        let (s, _, slab) = st.split();
        self.walk_out::<ANY, _, _>(&r, p, slab, &mut Walk::new(&r, a.2), s)
    }

    /// The closest hit along `a` in a loop built with `S`'s box test: walked inline
    /// (`single_in`) in the x86-64-v3 builds, by the walk specialised per axis permutation
    /// (`intersect`) in the baseline one. The same answer either way.
    #[inline(always)]
    pub fn closest_in<S: Slab>(&self, st: &mut TraceStacks<S>, a: Segment) -> Option<Hit> {
        if S::INLINE_WALKS {
            self.single_in::<false, _>(st, a)
        } else {
            self.intersect(a.0, a.1, a.2)
        }
    }

    /// Whether anything blocks `a` and `b` (any-hit queries), traced interleaved: the same
    /// answers as two calls of `occluded`.
    #[inline]
    pub fn occluded_pair(&self, a: Segment, b: Segment) -> (bool, bool) {
        with_stacks(|sa, sb| {
            let (ha, hb) = self.trace_pair::<true, true, _>(a, b, sa, sb, Sse);
            (ha.is_some(), hb.is_some())
        })
    }

    /// `occluded_pair` on the caller's stacks.
    #[inline(always)]
    pub fn occluded_pair_in<S: Slab>(
        &self,
        st: &mut TraceStacks<S>,
        a: Segment,
        b: Segment,
    ) -> (bool, bool) {
        let (sa, sb, slab) = st.split();
        let (ha, hb) = self.trace_pair::<true, true, _>(a, b, sa, sb, slab);
        (ha.is_some(), hb.is_some())
    }

    /// The closest hits along `a` and `b`, traced interleaved: the same answers as two
    /// calls of `intersect`.
    #[inline]
    pub fn intersect_pair(&self, a: Segment, b: Segment) -> (Option<Hit>, Option<Hit>) {
        with_stacks(|sa, sb| self.trace_pair::<false, false, _>(a, b, sa, sb, Sse))
    }

    #[inline(always)]
    fn trace_pair<const ANY_A: bool, const ANY_B: bool, S: Slab>(
        &self,
        a: Segment,
        b: Segment,
        sa: &mut [(u32, f32)],
        sb: &mut [(u32, f32)],
        slab: S,
    ) -> (Option<Hit>, Option<Hit>) {
        if self.wide.is_empty() || self.one_at_a_time {
            return (
                self.traverse::<ANY_A>(a.0, a.1, a.2),
                self.traverse::<ANY_B>(b.0, b.1, b.2),
            );
        }
        let (ra, rb) = (RayPre::new(a.0, a.1), RayPre::new(b.0, b.1));
        let (pa, pb) = (Dyn(ra.kx, ra.ky, ra.kz), Dyn(rb.kx, rb.ky, rb.kz));
        let mut wa = Walk::new(&ra, a.2);
        let mut wb = Walk::new(&rb, b.2);
        loop {
            if self.step8::<ANY_A, _, _>(&ra, pa, slab, &mut wa, sa) {
                return (
                    wa.best(),
                    self.walk_out::<ANY_B, _, _>(&rb, pb, slab, &mut wb, sb),
                );
            }
            if self.step8::<ANY_B, _, _>(&rb, pb, slab, &mut wb, sb) {
                return (
                    self.walk_out::<ANY_A, _, _>(&ra, pa, slab, &mut wa, sa),
                    wb.best(),
                );
            }
        }
    }
}
