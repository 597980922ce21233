//! The 4-wide BVH (`Bvh::widen`): the binary SAH tree collapsed so that every node holds up
//! to four children (Wald, Benthin and Boulos 2008, "Getting rid of packets"; Dammertz et
//! al. 2008, "Shallow bounding volume hierarchies for fast SIMD ray tracing of incoherent
//! rays"), each node's four boxes stored axis by axis (structure of arrays) so that one ray
//! is tested against all four on four SIMD lanes, and each leaf's (up to four) triangles
//! stored the same way (`Tri4`) for a four-lane watertight test. A node is collapsed by
//! opening, while fewer than four children remain, the interior child with the largest
//! surface area (the one a random ray is most likely to enter).
//!
//! The lane arithmetic is in `lanes.rs`; docs/path_tracing.md has the measurements.

use super::lanes::{slab4q, tri4, Ray4, Tri4, F4};
use super::{Aabb, Bvh};
use crate::nodes::trace::bvh::traverse::{with_stack, RayPre};
use crate::nodes::trace::bvh::Hit;

/// Marks an unused child slot.
const EMPTY: u32 = u32::MAX;
/// Marks a leaf child: `LEAF | leaf << 3 | count`, `leaf` indexing `Bvh::wide_tris`
/// (leaves hold at most 4 triangles).
pub(super) const LEAF: u32 = 1 << 31;
/// Triangle counts at or above this cannot be encoded; such scenes keep the binary tree.
pub(super) const MAX_TRIS: usize = 1 << 28;

/// A node of the 4-wide BVH in one cache line (64 bytes): the four child boxes quantised
/// to 8 bits per plane on a grid over the node's own box (Ylitie, Karras and Laine 2017,
/// "Efficient incoherent ray traversal on GPUs through compressed wide BVHs", section 3.1:
/// an origin, a power-of-two step per axis, and per child and plane an integer `q`, the
/// plane being `origin + q * 2^e`), rounded outward so that every decoded box holds its
/// child's exact box; and per child either an interior node (its index), a leaf
/// (`LEAF | leaf << 3 | count`) or nothing (`EMPTY`, its bit clear in `live`). The full
/// f32 boxes took two cache lines, and traversal waited on their loads
/// (docs/path_tracing.md).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Node4 {
    /// Lower corner of the quantisation grid.
    pub origin: [f32; 3],
    /// Per axis, the grid step `2^e` as its biased f32 exponent field (`e + 127`).
    pub exp: [u8; 3],
    /// Bit `l` set when child `l` is in use.
    pub live: u8,
    /// Lower planes, `lo[axis][lane]`, in grid steps from `origin`.
    pub lo: [[u8; 4]; 3],
    /// Upper planes, `hi[axis][lane]`.
    pub hi: [[u8; 4]; 3],
    /// Child node index or leaf code.
    pub child: [u32; 4],
}

impl Node4 {
    /// The grid step of `axis`.
    #[inline(always)]
    fn step(&self, axis: usize) -> f32 {
        f32::from_bits((self.exp[axis] as u32) << 23)
    }

    /// The decoded boxes, `(min[axis][lane], max[axis][lane])`: `origin + q * step` in f32
    /// (exact product, one rounding in the sum), the same operations the quantiser checked.
    #[inline(always)]
    pub fn boxes(&self) -> ([F4; 3], [F4; 3]) {
        let dec = |q: [u8; 4], o: f32, s: f32| -> F4 {
            [
                o + q[0] as f32 * s,
                o + q[1] as f32 * s,
                o + q[2] as f32 * s,
                o + q[3] as f32 * s,
            ]
        };
        let mut min = [[0.0; 4]; 3];
        let mut max = [[0.0; 4]; 3];
        for a in 0..3 {
            let s = self.step(a);
            min[a] = dec(self.lo[a], self.origin[a], s);
            max[a] = dec(self.hi[a], self.origin[a], s);
        }
        (min, max)
    }

    /// The decoded box of child `lane` (it holds the child's exact box).
    pub fn bounds(&self, lane: usize) -> Aabb {
        let (min, max) = self.boxes();
        Aabb {
            min: [min[0][lane], min[1][lane], min[2][lane]],
            max: [max[0][lane], max[1][lane], max[2][lane]],
        }
    }
}

/// Quantises the child boxes `kids` (at most four, each non-empty) into `n`'s grid:
/// origin at their union's lower corner, per axis the smallest power-of-two step with 255
/// steps spanning the union, each lower plane rounded down and each upper plane up, then
/// moved a step further while the f32 decoding (`Node4::boxes`) is not outside the exact
/// plane. False when a step would leave the normal f32 range (a scene over about 1e36
/// wide): the caller keeps the binary tree.
fn quantise(n: &mut Node4, kids: &[Aabb]) -> bool {
    let mut u = Aabb::EMPTY;
    for b in kids {
        u = u.union(b);
    }
    n.origin = u.min;
    for a in 0..3 {
        let ext = u.max[a] as f64 - u.min[a] as f64;
        // Smallest e with 255 * 2^e >= ext, kept normal (-126..=119, so 255 * 2^e is
        // finite).
        let mut e = -126i32;
        while 255.0 * 2f64.powi(e) < ext {
            e += 1;
            if e > 119 {
                return false;
            }
        }
        n.exp[a] = (e + 127) as u8;
        let (o, s) = (n.origin[a], n.step(a));
        let dec = |q: u32| o + q as f32 * s;
        for (l, b) in kids.iter().enumerate() {
            let mut q = (((b.min[a] as f64 - o as f64) / s as f64).floor()).clamp(0.0, 255.0) as u32;
            while q > 0 && dec(q) > b.min[a] {
                q -= 1;
            }
            n.lo[a][l] = q as u8;
            let mut q = (((b.max[a] as f64 - o as f64) / s as f64).ceil()).clamp(0.0, 255.0) as u32;
            while q < 255 && dec(q) < b.max[a] {
                q += 1;
            }
            n.hi[a][l] = q as u8;
            if dec(n.lo[a][l] as u32) > b.min[a] || dec(n.hi[a][l] as u32) < b.max[a] {
                return false;
            }
        }
    }
    n.live = (1u8 << kids.len()) - 1;
    true
}

/// Collapses the binary tree of `bvh` (root first, children of an interior node at
/// `first` and `first + 1`; leaves of at most 4 triangles) into 4-wide nodes, root first,
/// and the leaves' triangles packed four to a `Tri4`. A binary subtree over at most four
/// triangles becomes one wide leaf (its triangles are contiguous, as the tree was flattened
/// depth first): the four-lane test costs about the same for one triangle as for four, so
/// fewer, fuller leaves mean fewer nodes visited. Empty when there is nothing to collapse
/// or the leaves cannot be encoded (`MAX_TRIS` triangles or more, or a leaf over 4
/// triangles): the binary tree is traversed then.
pub fn collapse(bvh: &Bvh) -> (Vec<Node4>, Vec<Tri4>) {
    let nodes = &bvh.nodes;
    let mut out = Vec::with_capacity(nodes.len() / 2 + 1);
    let mut leaves = Vec::with_capacity(nodes.len() / 2 + 1);
    if nodes.is_empty() || bvh.tris.len() >= MAX_TRIS || nodes.iter().any(|n| n.count > 4) {
        return (out, leaves);
    }
    // Triangles under each binary node (`first` of the leftmost leaf, count); children
    // come after their parent, so a backward pass sees them first.
    let mut under = vec![(0u32, 0u32); nodes.len()];
    for k in (0..nodes.len()).rev() {
        let n = &nodes[k];
        under[k] = if n.count > 0 {
            (n.first, n.count)
        } else {
            let (l, r) = (under[n.first as usize], under[n.first as usize + 1]);
            (l.0, l.1 + r.1)
        };
    }
    let is_leaf = |k: usize| under[k].1 <= 4;
    let fail = (Vec::new(), Vec::new());
    if is_leaf(0) {
        // A single leaf: a root with one child.
        let mut n = empty_node();
        set_lane(&mut n, 0, bvh, under[0], &mut leaves);
        if !quantise(&mut n, &[nodes[0].bounds]) {
            return fail;
        }
        out.push(n);
        return (out, leaves);
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
                .filter(|(_, &k)| !is_leaf(k))
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
        let boxes: Vec<Aabb> = kids.iter().map(|&k| nodes[k].bounds).collect();
        if !quantise(&mut n, &boxes) {
            return fail;
        }
        for (lane, &k) in kids.iter().enumerate() {
            set_lane(&mut n, lane, bvh, under[k], &mut leaves);
            if !is_leaf(k) {
                n.child[lane] = out.len() as u32;
                todo.push((k, out.len()));
                out.push(empty_node());
            }
        }
        out[slot] = n;
    }
    (out, leaves)
}

fn empty_node() -> Node4 {
    Node4 {
        origin: [0.0; 3],
        exp: [127; 3],
        live: 0,
        lo: [[0; 4]; 3],
        hi: [[0; 4]; 3],
        child: [EMPTY; 4],
    }
}

/// Makes a binary node child `lane` of `n` when it is a leaf (at most four
/// triangles, `under`: first, count): those packed into a new `Tri4` (the caller sets an
/// interior child's index; `quantise` stores the boxes).
fn set_lane(
    n: &mut Node4,
    lane: usize,
    bvh: &Bvh,
    under: (u32, u32),
    leaves: &mut Vec<Tri4>,
) {
    let (first, count) = under;
    if count <= 4 {
        let r = first as usize..(first + count) as usize;
        n.child[lane] = LEAF | (leaves.len() as u32) << 3 | count;
        leaves.push(Tri4::pack(&bvh.tris[r.clone()], &bvh.prim[r]));
    }
}

impl Bvh {
    /// Closest-hit (or, with `ANY`, any-hit) traversal of the 4-wide tree, front to back:
    /// the four boxes of a node are tested on four lanes, the entered children sorted by
    /// entry distance (not for any-hit), the nearest visited next and the others pushed far
    /// to near; a popped entry is skipped once a hit closer than its entry distance has
    /// been found.
    pub(super) fn traverse4<const ANY: bool, const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        r: &RayPre,
        tmax: f32,
    ) -> Option<Hit> {
        with_stack(|stack| self.walk4::<ANY, KX, KY, KZ>(r, tmax, stack))
    }

    #[inline(always)]
    fn walk4<const ANY: bool, const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        r: &RayPre,
        tmax: f32,
        stack: &mut [(u32, f32)],
    ) -> Option<Hit> {
        let ray = Ray4::new(r);
        let mut best: Option<Hit> = None;
        let mut tmax = tmax;
        let mut sp = 0usize;
        let mut c = 0u32;
        'outer: loop {
            if c & LEAF == 0 {
                let n = &self.wide[c as usize];
                let step = [n.step(0), n.step(1), n.step(2)];
                let (m, te) = slab4q(&ray, n.origin, step, &n.lo, &n.hi, tmax);
                let mut m = m & n.live as u32;
                if m != 0 {
                    let first = m.trailing_zeros() as usize;
                    m &= m - 1;
                    if m == 0 {
                        c = n.child[first];
                        continue;
                    }
                    if ANY {
                        // Any hit ends the query, so the order does not matter: push the
                        // other entered children unsorted.
                        while m != 0 {
                            let l = m.trailing_zeros() as usize;
                            m &= m - 1;
                            if sp < stack.len() {
                                stack[sp] = (n.child[l], te[l]);
                                sp += 1;
                            }
                        }
                        c = n.child[first];
                        continue;
                    }
                    // Two to four children entered: sort them near to far (insertion sort
                    // on at most four), visit the nearest, push the rest far to near.
                    let mut ids = [first; 4];
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
                        if sp < stack.len() {
                            stack[sp] = (n.child[l], te[l]);
                            sp += 1;
                        }
                    }
                    c = n.child[ids[0]];
                    continue;
                }
            } else {
                let q = &self.wide_tris[((c & !LEAF) >> 3) as usize];
                let found = tri4::<ANY, KX, KY, KZ>(r, q, (c & 7) as usize, &mut tmax, |t, u, v, l| {
                    best = Some(Hit {
                        t,
                        prim: q.prim[l],
                        u,
                        v,
                    })
                });
                if ANY && found {
                    return best;
                }
            }
            while sp > 0 {
                sp -= 1;
                let (n, t) = stack[sp];
                if t <= tmax {
                    c = n;
                    continue 'outer;
                }
            }
            return best;
        }
    }
}
