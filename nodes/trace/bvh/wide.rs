//! The 8-wide BVH (`Bvh::widen`): the binary tree collapsed so that every node holds up
//! to eight children (Wald, Benthin and Boulos 2008, "Getting rid of packets"; Dammertz et
//! al. 2008, "Shallow bounding volume hierarchies for fast SIMD ray tracing of incoherent
//! rays"; Embree's BVH8), each node's eight boxes stored axis by axis (structure of arrays)
//! so that one ray is tested against all eight on eight SIMD lanes, and each leaf's (up to
//! four) triangles stored the same way (`Tri4`) for a four-lane watertight test. Which
//! binary subtrees become a node's children is solved for the least surface-area cost
//! (`slots.rs`). Eight children rather than four: a walk takes half as many node steps,
//! each dearer, and the path tracer got faster on both bench scenes (docs/path_tracing.md,
//! "How it runs", has the timings).
//!
//! The lane arithmetic is in `lanes.rs`; docs/path_tracing.md has the measurements.

use super::lanes::{tri4, Axes, Fixed, RayBox, Slab, Sse, Tri4, F8};
use super::slots::{subtrees, Slots};
use super::{Bvh, BvhNode, W};
use crate::bvh::traverse::{with_stack, RayPre};
use crate::bvh::Hit;
use rayon::prelude::*;

/// Marks an unused child slot.
const EMPTY: u32 = u32::MAX;
/// Marks a leaf child: `LEAF | leaf << 3 | count`, `leaf` indexing `Bvh::wide_tris`
/// (leaves hold at most 4 triangles).
pub(super) const LEAF: u32 = 1 << 31;
/// Triangle counts at or above this cannot be encoded; such scenes keep the binary tree.
pub(super) const MAX_TRIS: usize = 1 << 28;

/// A node of the 8-wide BVH: eight child boxes (per axis, per lane), and per child either
/// an interior node (its index), a leaf (`LEAF | leaf << 3 | count`) or nothing (`EMPTY`,
/// whose box is empty: min = +inf, max = -inf, so no ray enters it). 224 bytes, aligned to
/// 32: a node spans four cache lines whether or not it starts on one, and without padding
/// to 256 bytes an eighth more of a large tree stays in the cache.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct Node8 {
    /// Lower corners, `min[axis][lane]`.
    pub min: [F8; 3],
    /// Upper corners, `max[axis][lane]`.
    pub max: [F8; 3],
    /// Child node index or leaf code.
    pub child: [u32; W],
}

/// Collapses the binary tree of `bvh` (root first, children of an interior node at
/// `first` and `first + 1`; leaves of at most 4 triangles) into 8-wide nodes, root first,
/// and the leaves' triangles packed four to a `Tri4`. A binary subtree over at most four
/// triangles becomes one wide leaf (its triangles are contiguous, as the tree was flattened
/// depth first): the four-lane test costs about the same for one triangle as for four, so
/// fewer, fuller leaves mean fewer nodes visited. Empty when there is nothing to collapse
/// or the leaves cannot be encoded (`MAX_TRIS` triangles or more, or a leaf over 4
/// triangles): the binary tree is traversed then.
pub fn collapse(bvh: &Bvh) -> (Vec<Node8>, Vec<Tri4>) {
    let nodes = &bvh.nodes;
    let mut out = Vec::with_capacity(nodes.len() / 2 + 1);
    // (first, count) of each wide leaf's triangles, packed at the end.
    let mut leaves: Vec<(u32, u32)> = Vec::with_capacity(nodes.len() / 2 + 1);
    if nodes.is_empty() || bvh.tris.len() >= MAX_TRIS || nodes.iter().any(|n| n.count > 4) {
        return (out, Vec::new());
    }
    let under = subtrees(nodes);
    let slots = Slots::solve(nodes, &under);
    if slots.is_leaf(0) {
        // A single leaf: a root with one child.
        let mut n = empty_node();
        set_box(&mut n, 0, &nodes[0]);
        n.child[0] = add_leaf(&mut leaves, under[0]);
        out.push(n);
        return (out, pack(bvh, &leaves));
    }
    out.push(empty_node());
    // (binary node to expand, slot in `out`)
    let mut todo = vec![(0usize, 0usize)];
    while let Some((b, slot)) = todo.pop() {
        let kids = slots.children(nodes, b);
        let mut n = empty_node();
        for (lane, &k) in kids.iter().enumerate() {
            set_box(&mut n, lane, &nodes[k]);
            n.child[lane] = if slots.is_leaf(k) {
                add_leaf(&mut leaves, under[k])
            } else {
                todo.push((k, out.len()));
                out.push(empty_node());
                (out.len() - 1) as u32
            };
        }
        out[slot] = n;
    }
    (out, pack(bvh, &leaves))
}

/// The leaves' triangles (first, count) packed into `Tri4`s, on every core.
fn pack(bvh: &Bvh, leaves: &[(u32, u32)]) -> Vec<Tri4> {
    leaves
        .par_iter()
        .map(|&(first, count)| {
            let r = first as usize..(first + count) as usize;
            Tri4::pack(&bvh.tris[r.clone()], &bvh.prim[r])
        })
        .collect()
}

fn empty_node() -> Node8 {
    Node8 {
        min: [[f32::INFINITY; W]; 3],
        max: [[f32::NEG_INFINITY; W]; 3],
        child: [EMPTY; W],
    }
}

/// Puts the box of binary node `b` in `lane` of `n`.
fn set_box(n: &mut Node8, lane: usize, b: &BvhNode) {
    for a in 0..3 {
        n.min[a][lane] = b.bounds.min[a];
        n.max[a][lane] = b.bounds.max[a];
    }
}

/// The child code of a new wide leaf over the triangles `(first, count)`, packed into a
/// `Tri4` at the end.
fn add_leaf(leaves: &mut Vec<(u32, u32)>, (first, count): (u32, u32)) -> u32 {
    leaves.push((first, count));
    LEAF | ((leaves.len() - 1) as u32) << 3 | count
}

/// One ray's state in the 8-wide traversal, advanced one node or leaf at a time by
/// `Bvh::step8` (so that two rays can be advanced in turn, `Bvh::trace_pair`).
pub(super) struct Walk {
    ray: RayBox,
    tmax: f32,
    best: Option<Hit>,
    /// Entries on this ray's stack.
    sp: usize,
    /// The node or leaf to visit next.
    c: u32,
}

impl Walk {
    #[inline(always)]
    pub(super) fn new(r: &RayPre, tmax: f32) -> Walk {
        Walk {
            ray: RayBox::new(r),
            tmax,
            best: None,
            sp: 0,
            c: 0,
        }
    }

    /// The closest hit found so far (the any hit, for an any-hit query).
    #[inline(always)]
    pub(super) fn best(&self) -> Option<Hit> {
        self.best
    }
}

impl Bvh {
    /// Makes `c` the next node or leaf of `w`, and asks the cache for its data now, so that
    /// the load overlaps the other ray's step of a pair.
    #[inline(always)]
    fn go(&self, w: &mut Walk, c: u32) {
        w.c = c;
        #[cfg(target_arch = "x86_64")]
        if self.prefetch {
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            let (p, lines) = if c & LEAF == 0 {
                (self.wide.as_ptr().wrapping_add(c as usize) as *const i8, 4)
            } else {
                let q = self
                    .wide_tris
                    .as_ptr()
                    .wrapping_add(((c & !LEAF) >> 3) as usize);
                (q as *const i8, 3)
            };
            for k in 0..lines {
                // SAFETY: a prefetch reads nothing and cannot fault, whatever the address.
                unsafe { _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(64 * k)) };
            }
        }
    }

    /// Closest-hit (or, with `ANY`, any-hit) traversal of the 8-wide tree, front to back:
    /// the eight boxes of a node are tested on eight lanes, the entered children sorted by
    /// entry distance (not for any-hit), the nearest visited next and the others pushed far
    /// to near; a popped entry is skipped once a hit closer than its entry distance has
    /// been found.
    pub(super) fn traverse8<const ANY: bool, const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        r: &RayPre,
        tmax: f32,
    ) -> Option<Hit> {
        with_stack(|stack| {
            let w = &mut Walk::new(r, tmax);
            self.walk_out::<ANY, _, _>(r, Fixed::<KX, KY, KZ>, Sse, w, stack)
        })
    }

    /// Advances `w` until its query is finished; its answer.
    #[inline(always)]
    pub(super) fn walk_out<const ANY: bool, P: Axes, S: Slab>(
        &self,
        r: &RayPre,
        axes: P,
        slab: S,
        w: &mut Walk,
        stack: &mut [(u32, f32)],
    ) -> Option<Hit> {
        while !self.step8::<ANY, _, _>(r, axes, slab, w, stack) {}
        w.best
    }

    /// Advances `w` by one node (test its eight boxes, go to the nearest entered child,
    /// push the others) or one leaf (test its triangles), then, when nothing was entered,
    /// pops the next entry not farther than the closest hit. Returns true when the query
    /// is finished (stack empty, or an any-hit query found a hit); `w.best` is its answer.
    #[inline(always)]
    pub(super) fn step8<const ANY: bool, P: Axes, S: Slab>(
        &self,
        r: &RayPre,
        axes: P,
        slab: S,
        w: &mut Walk,
        stack: &mut [(u32, f32)],
    ) -> bool {
        let c = w.c;
        if c & LEAF == 0 {
            let n = &self.wide[c as usize];
            let (mut m, te) = slab.slab8(&w.ray, &n.min, &n.max, w.tmax);
            if m != 0 {
                let first = m.trailing_zeros() as usize;
                m &= m - 1;
                if m == 0 {
                    self.go(w, n.child[first]);
                    return false;
                }
                if ANY {
                    // Any hit ends the query, so the order does not matter: push the
                    // other entered children unsorted.
                    while m != 0 {
                        let l = m.trailing_zeros() as usize;
                        m &= m - 1;
                        if w.sp < stack.len() {
                            stack[w.sp] = (n.child[l], te[l]);
                            w.sp += 1;
                        }
                    }
                    self.go(w, n.child[first]);
                    return false;
                }
                if m & (m - 1) == 0 {
                    // Two children entered (the common case): visit the nearer, push the
                    // other, chosen by selects rather than the sort's branches (ties keep
                    // lane order, as the sort does).
                    let second = m.trailing_zeros() as usize;
                    let swap = te[second] < te[first];
                    let (near, far) = if swap {
                        (second, first)
                    } else {
                        (first, second)
                    };
                    if w.sp < stack.len() {
                        stack[w.sp] = (n.child[far], te[far]);
                        w.sp += 1;
                    }
                    self.go(w, n.child[near]);
                    return false;
                }
                // Three or more children entered: sort them near to far (insertion sort),
                // visit the nearest, push the rest far to near.
                let mut ids = [first; W];
                let mut k = 1;
                while m != 0 {
                    let l = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let mut j = k;
                    while j > 0 && te[ids[j - 1]] > te[l] {
                        ids[j] = ids[j - 1];
                        j -= 1;
                    }
                    ids[j] = l;
                    k += 1;
                }
                for &l in ids[1..k].iter().rev() {
                    if w.sp < stack.len() {
                        stack[w.sp] = (n.child[l], te[l]);
                        w.sp += 1;
                    }
                }
                self.go(w, n.child[ids[0]]);
                return false;
            }
        } else {
            let q = &self.wide_tris[((c & !LEAF) >> 3) as usize];
            let best = &mut w.best;
            let found = tri4::<ANY, P>(r, axes, q, (c & 7) as usize, &mut w.tmax, |t, u, v, l| {
                *best = Some(Hit {
                    t,
                    prim: q.prim[l],
                    u,
                    v,
                })
            });
            if ANY && found {
                return true;
            }
        }
        while w.sp > 0 {
            w.sp -= 1;
            let (n, t) = stack[w.sp];
            if t <= w.tmax {
                self.go(w, n);
                return false;
            }
        }
        true
    }
}
