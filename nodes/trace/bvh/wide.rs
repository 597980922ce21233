//! An optional 4-wide BVH (`Bvh::widen`): the binary SAH tree collapsed so that every node
//! holds up to four children (Wald, Benthin and Boulos 2008, "Getting rid of packets";
//! Dammertz et al. 2008, "Shallow bounding volume hierarchies for fast SIMD ray tracing of
//! incoherent rays"), each node's four boxes stored axis by axis (structure of arrays) so
//! that one ray can be tested against all four on four lanes. A node is collapsed by
//! opening, while fewer than four children remain, the interior child with the largest
//! surface area (the one a random ray is most likely to enter).
//!
//! Not built by default: measured on 2026-12-02 (docs/path_tracing.md) it was no faster
//! than the binary tree on the Cornell box or the igea scene; the lane loops compile mostly
//! to scalar code (explicit SIMD would need `std::arch` loads, which are unsafe).

use super::{Bvh, BvhNode};
use crate::nodes::trace::bvh::traverse::{tri_test, RayPre};
use crate::nodes::trace::bvh::Hit;

/// Marks an unused child slot.
const EMPTY: u32 = u32::MAX;
/// Marks a leaf child: `LEAF | first << 3 | count` (leaves hold at most 4 triangles).
pub(super) const LEAF: u32 = 1 << 31;
/// Triangle counts at or above this cannot be encoded; such scenes keep the binary tree.
pub(super) const MAX_TRIS: usize = 1 << 28;

/// A node of the 4-wide BVH: four child boxes (per axis, per lane), and per child either
/// an interior node (its index), a leaf (`LEAF | first << 3 | count`) or nothing (`EMPTY`).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Node4 {
    /// Lower corners, `min[axis][lane]`.
    pub min: [[f32; 4]; 3],
    /// Upper corners, `max[axis][lane]`.
    pub max: [[f32; 4]; 3],
    /// Child node index or leaf code.
    pub child: [u32; 4],
}

/// Collapses the binary tree `nodes` (root first, children of an interior node at `first`
/// and `first + 1`; leaves of at most 4 triangles) into 4-wide nodes, root first. Empty
/// when there is nothing to collapse or the leaves cannot be encoded (`tris >= MAX_TRIS`
/// or a leaf over 4 triangles): the binary tree is traversed then.
pub fn collapse(nodes: &[BvhNode], tris: usize) -> Vec<Node4> {
    let mut out = Vec::with_capacity(nodes.len() / 2 + 1);
    if nodes.is_empty() || tris >= MAX_TRIS || nodes.iter().any(|n| n.count > 4) {
        return out;
    }
    if nodes[0].count > 0 {
        // A single leaf: a root with one child.
        let mut n = empty_node();
        set_lane(&mut n, 0, &nodes[0], nodes[0].first);
        out.push(n);
        return out;
    }
    out.push(empty_node());
    // (binary node to expand, slot in `out`)
    let mut todo = vec![(0usize, 0usize)];
    while let Some((b, slot)) = todo.pop() {
        let first = nodes[b].first as usize;
        let mut kids = vec![first, first + 1];
        while kids.len() < 4 {
            // Open the interior child of largest area.
            let pick = kids
                .iter()
                .enumerate()
                .filter(|(_, &k)| nodes[k].count == 0)
                .max_by(|a, b| {
                    let (sa, sb) = (nodes[*a.1].bounds.half_area(), nodes[*b.1].bounds.half_area());
                    sa.total_cmp(&sb)
                })
                .map(|(i, _)| i);
            let Some(i) = pick else { break };
            let k = kids.swap_remove(i);
            let f = nodes[k].first as usize;
            kids.push(f);
            kids.push(f + 1);
        }
        let mut n = empty_node();
        for (lane, &k) in kids.iter().enumerate() {
            if nodes[k].count > 0 {
                set_lane(&mut n, lane, &nodes[k], nodes[k].first);
            } else {
                let idx = out.len();
                out.push(empty_node());
                set_lane(&mut n, lane, &nodes[k], idx as u32);
                todo.push((k, idx));
            }
        }
        out[slot] = n;
    }
    out
}

fn empty_node() -> Node4 {
    Node4 {
        min: [[0.0; 4]; 3],
        max: [[0.0; 4]; 3],
        child: [EMPTY; 4],
    }
}

fn set_lane(n: &mut Node4, lane: usize, b: &BvhNode, child: u32) {
    for k in 0..3 {
        n.min[k][lane] = b.bounds.min[k];
        n.max[k][lane] = b.bounds.max[k];
    }
    n.child[lane] = if b.count > 0 {
        LEAF | child << 3 | b.count
    } else {
        child
    };
}

/// Entry distances of the ray into the four boxes of `n` (slab test on four lanes; the
/// near plane per axis is chosen once per ray from the direction's sign), `INFINITY`
/// where a box is missed or before `tmax` is not reached. Round-off is guarded as in the
/// binary traversal (Ize 2013: the exit distance is widened by 1 + 2 gamma(3)).
#[inline(always)]
#[allow(clippy::needless_range_loop)] // lane loops index several arrays in step
fn entry4(r: &RayPre, n: &Node4, tmax: f32) -> [f32; 4] {
    let mut t0 = [0.0f32; 4];
    let mut t1 = [tmax; 4];
    for k in 0..3 {
        let (near, far) = if r.inv[k] >= 0.0 {
            (&n.min[k], &n.max[k])
        } else {
            (&n.max[k], &n.min[k])
        };
        for l in 0..4 {
            let ta = (near[l] - r.org[k]) * r.inv[k];
            let tb = (far[l] - r.org[k]) * r.inv[k];
            // Plain comparisons (maxps/minps): a NaN from 0 * inf keeps the previous bound.
            t0[l] = if ta > t0[l] { ta } else { t0[l] };
            t1[l] = if tb < t1[l] { tb } else { t1[l] };
        }
    }
    let mut out = [f32::INFINITY; 4];
    for l in 0..4 {
        if t0[l] <= t1[l] * 1.000_000_4 && n.child[l] != EMPTY {
            out[l] = t0[l];
        }
    }
    out
}

impl Bvh {
    /// Closest-hit (or, with `ANY`, any-hit) traversal of the 4-wide tree, front to back:
    /// the children a ray enters are pushed far to near, and a popped entry is skipped once
    /// a hit closer than its entry distance has been found.
    #[allow(clippy::needless_range_loop)] // lane loops index several arrays in step
    pub(super) fn traverse4<const ANY: bool, const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        r: &RayPre,
        tmax: f32,
    ) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut tmax = tmax;
        // (node or leaf code, entry distance). A 4-wide node adds at most three pending
        // entries per level, and SAH trees over millions of triangles stay under 20 levels.
        let mut stack = [(0u32, 0.0f32); 64];
        let mut sp = 1usize;
        while sp > 0 {
            sp -= 1;
            let (c, t) = stack[sp];
            if t > tmax {
                continue;
            }
            if c & LEAF != 0 {
                let s = ((c & !LEAF) >> 3) as usize;
                for i in s..s + (c & 7) as usize {
                    if let Some((t, u, v)) = tri_test::<KX, KY, KZ>(r, &self.tris[i], tmax) {
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
                continue;
            }
            let n = &self.wide[c as usize];
            let te = entry4(r, n, tmax);
            // Sort the entered lanes far to near (at most four: insertion sort).
            let mut order = [0usize; 4];
            let mut m = 0;
            for l in 0..4 {
                if te[l] < f32::INFINITY {
                    let mut j = m;
                    while j > 0 && te[order[j - 1]] < te[l] {
                        order[j] = order[j - 1];
                        j -= 1;
                    }
                    order[j] = l;
                    m += 1;
                }
            }
            for &l in &order[..m] {
                if sp < stack.len() {
                    stack[sp] = (n.child[l], te[l]);
                    sp += 1;
                }
            }
        }
        best
    }
}
