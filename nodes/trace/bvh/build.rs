//! BVH construction: top-down binned SAH (Wald 2007), subtrees built in parallel with
//! rayon, then flattened depth-first with the triangles copied into BVH order.

use super::{Aabb, Bvh, BvhNode};
use crate::nodes::trace::sampling::V3;

const LEAF_MAX: usize = 4;
const BINS: usize = 16;
const PAR_THRESHOLD: usize = 4096;
/// Sets of at most this many triangles are split by the full SAH sweep (`sweep_split`)
/// instead of binning.
const SWEEP_MAX: usize = 1024;

enum BuildNode {
    Leaf(Aabb, Vec<u32>),
    Inner(Aabb, Box<BuildNode>, Box<BuildNode>),
}

struct PrimInfo {
    bounds: Aabb,
    centroid: V3,
}

fn build_rec(info: &[PrimInfo], mut ids: Vec<u32>) -> BuildNode {
    let mut bounds = Aabb::EMPTY;
    let mut cb = Aabb::EMPTY;
    for &i in &ids {
        bounds = bounds.union(&info[i as usize].bounds);
        cb.grow(info[i as usize].centroid);
    }
    let n = ids.len();
    if n <= 1 {
        return BuildNode::Leaf(bounds, ids);
    }
    if n <= SWEEP_MAX {
        if let Some((left, right)) = sweep_split(info, &ids, &bounds) {
            return join_children(info, bounds, left, right);
        }
        return BuildNode::Leaf(bounds, ids);
    }
    // Binned SAH over the axis of largest centroid extent and the two others.
    let mut best = (f32::INFINITY, 0usize, 0usize); // (cost, axis, split bin)
    for axis in 0..3 {
        let ext = cb.max[axis] - cb.min[axis];
        if ext <= 0.0 {
            continue;
        }
        let k = BINS as f32 * (1.0 - 1e-5) / ext;
        let mut bin_b = [Aabb::EMPTY; BINS];
        let mut bin_n = [0usize; BINS];
        for &i in &ids {
            let p = &info[i as usize];
            let b = (((p.centroid[axis] - cb.min[axis]) * k) as usize).min(BINS - 1);
            bin_n[b] += 1;
            bin_b[b] = bin_b[b].union(&p.bounds);
        }
        // Sweep from the right, then from the left (Wald 2007, section 3).
        let mut right_area = [0.0f32; BINS];
        let mut right_n = [0usize; BINS];
        let mut acc = Aabb::EMPTY;
        let mut cnt = 0;
        for b in (1..BINS).rev() {
            acc = acc.union(&bin_b[b]);
            cnt += bin_n[b];
            right_area[b] = acc.half_area();
            right_n[b] = cnt;
        }
        let mut acc = Aabb::EMPTY;
        let mut cnt = 0;
        for b in 0..BINS - 1 {
            acc = acc.union(&bin_b[b]);
            cnt += bin_n[b];
            if cnt == 0 || right_n[b + 1] == 0 {
                continue;
            }
            let cost = acc.half_area() * cnt as f32 + right_area[b + 1] * right_n[b + 1] as f32;
            if cost < best.0 {
                best = (cost, axis, b);
            }
        }
    }
    let leaf_cost = bounds.half_area() * n as f32;
    // Traversal cost 1/8 of a triangle test, as in PBRT (Pharr et al., 4th ed., 7.3.2).
    let split_cost = 0.125 * bounds.half_area() + best.0;
    if best.0.is_infinite() {
        // All centroids coincide: a leaf if small, else split the list in half.
        if n <= LEAF_MAX {
            return BuildNode::Leaf(bounds, ids);
        }
        let right = ids.split_off(n / 2);
        return join_children(info, bounds, ids, right);
    }
    if n <= LEAF_MAX && split_cost >= leaf_cost {
        return BuildNode::Leaf(bounds, ids);
    }
    let (_, axis, split) = best;
    let ext = cb.max[axis] - cb.min[axis];
    let k = BINS as f32 * (1.0 - 1e-5) / ext;
    let (left, right): (Vec<u32>, Vec<u32>) = ids.into_iter().partition(|&i| {
        let c = info[i as usize].centroid[axis];
        (((c - cb.min[axis]) * k) as usize).min(BINS - 1) <= split
    });
    join_children(info, bounds, left, right)
}

/// The split of `ids` (bounds `bounds`) of least SAH cost over every position of the
/// centroids sorted on each axis (the full sweep of MacDonald and Booth 1990, which
/// binning approximates): `None` when a leaf costs less (only for at most `LEAF_MAX`
/// triangles; larger sets are always split, the halves of the sorted list if nothing
/// better).
fn sweep_split(info: &[PrimInfo], ids: &[u32], bounds: &Aabb) -> Option<(Vec<u32>, Vec<u32>)> {
    let n = ids.len();
    let mut best = (f32::INFINITY, 0usize, 0usize); // (cost, axis, left count)
    let mut sorted: [Vec<u32>; 3] = [ids.to_vec(), ids.to_vec(), ids.to_vec()];
    let mut right_area = vec![0.0f32; n];
    for (axis, order) in sorted.iter_mut().enumerate() {
        sort_on_axis(info, order, axis);
        let mut acc = Aabb::EMPTY;
        for k in (1..n).rev() {
            acc = acc.union(&info[order[k] as usize].bounds);
            right_area[k] = acc.half_area();
        }
        let mut acc = Aabb::EMPTY;
        for k in 1..n {
            acc = acc.union(&info[order[k - 1] as usize].bounds);
            let cost = acc.half_area() * k as f32 + right_area[k] * (n - k) as f32;
            if cost < best.0 {
                best = (cost, axis, k);
            }
        }
    }
    let leaf_cost = bounds.half_area() * n as f32;
    // Traversal cost 1/8 of a triangle test, as in PBRT (Pharr et al., 4th ed., 7.3.2).
    let split_cost = 0.125 * bounds.half_area() + best.0;
    if n <= LEAF_MAX && split_cost >= leaf_cost {
        return None;
    }
    let (_, axis, k) = if best.0.is_finite() { best } else { (0.0, 0, n / 2) };
    let mut order = std::mem::take(&mut sorted[axis]);
    let right = order.split_off(k);
    Some((order, right))
}

/// Sorts `ids` by their centroids' coordinate on `axis` (ties by index, so the order is
/// the same on every run).
fn sort_on_axis(info: &[PrimInfo], ids: &mut [u32], axis: usize) {
    ids.sort_by(|&a, &b| {
        let (ca, cb) = (info[a as usize].centroid[axis], info[b as usize].centroid[axis]);
        ca.total_cmp(&cb).then(a.cmp(&b))
    });
}

/// A triangle's box and centroid for the build. The vertex centroid (not the box centre)
/// tells apart the two halves of a quad, whose boxes coincide.
fn prim_info(t: &[V3; 3]) -> PrimInfo {
    let mut bounds = Aabb::EMPTY;
    for p in t {
        bounds.grow(*p);
    }
    let c = |k: usize| (t[0][k] + t[1][k] + t[2][k]) / 3.0;
    PrimInfo {
        bounds,
        centroid: [c(0), c(1), c(2)],
    }
}

fn join_children(info: &[PrimInfo], bounds: Aabb, left: Vec<u32>, right: Vec<u32>) -> BuildNode {
    let (l, r) = if left.len() + right.len() > PAR_THRESHOLD {
        rayon::join(|| build_rec(info, left), || build_rec(info, right))
    } else {
        (build_rec(info, left), build_rec(info, right))
    };
    BuildNode::Inner(bounds, Box::new(l), Box::new(r))
}

impl Bvh {
    /// Builds the BVH over `tris` (any order; degenerate triangles are kept and never hit),
    /// and its 4-wide form (`widen`), which the queries traverse.
    pub fn build(tris: &[[V3; 3]]) -> Bvh {
        let info: Vec<PrimInfo> = tris.iter().map(prim_info).collect();
        let mut bvh = Bvh::default();
        if tris.is_empty() {
            return bvh;
        }
        let root = build_rec(&info, (0..tris.len() as u32).collect());
        bvh.nodes.push(BvhNode {
            bounds: Aabb::EMPTY,
            first: 0,
            count: 0,
        });
        bvh.flatten(root, 0, tris);
        bvh.widen();
        bvh
    }

    fn flatten(&mut self, n: BuildNode, slot: usize, tris: &[[V3; 3]]) {
        match n {
            BuildNode::Leaf(b, ids) => {
                self.nodes[slot] = BvhNode {
                    bounds: b,
                    first: self.tris.len() as u32,
                    count: ids.len() as u32,
                };
                for i in ids {
                    self.tris.push(tris[i as usize]);
                    self.prim.push(i);
                }
            }
            BuildNode::Inner(b, l, r) => {
                let first = self.nodes.len();
                let empty = BvhNode {
                    bounds: Aabb::EMPTY,
                    first: 0,
                    count: 0,
                };
                self.nodes.push(empty);
                self.nodes.push(empty);
                self.nodes[slot] = BvhNode {
                    bounds: b,
                    first: first as u32,
                    count: 0,
                };
                self.flatten(*l, first, tris);
                self.flatten(*r, first + 1, tris);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nodes::trace::sampling::Pcg32;

    fn sah(info: &[PrimInfo], ids: &[u32]) -> f32 {
        let mut b = Aabb::EMPTY;
        ids.iter().for_each(|&i| b = b.union(&info[i as usize].bounds));
        b.half_area() * ids.len() as f32
    }

    /// The sweep's split costs what the best split of the centroids sorted on some axis
    /// costs, each candidate's two boxes recomputed from scratch (not incrementally).
    #[test]
    fn sweep_split_finds_the_cheapest_sorted_split() {
        let mut r = Pcg32::new(3, 5);
        for n in [2usize, 3, 5, 9, 17, 40, 64] {
            let tris: Vec<[V3; 3]> = (0..n)
                .map(|_| {
                    let c = [r.next_f32() * 8.0, r.next_f32(), r.next_f32() * 3.0];
                    let mut t = [c; 3];
                    for p in &mut t[1..] {
                        for x in p.iter_mut() {
                            *x += r.next_f32() * 0.5;
                        }
                    }
                    t
                })
                .collect();
            let info: Vec<PrimInfo> = tris.iter().map(prim_info).collect();
            let ids: Vec<u32> = (0..n as u32).collect();
            let mut bounds = Aabb::EMPTY;
            ids.iter().for_each(|&i| bounds = bounds.union(&info[i as usize].bounds));
            let mut naive = f32::INFINITY;
            for axis in 0..3 {
                let mut o = ids.clone();
                sort_on_axis(&info, &mut o, axis);
                for k in 1..n {
                    naive = naive.min(sah(&info, &o[..k]) + sah(&info, &o[k..]));
                }
            }
            match sweep_split(&info, &ids, &bounds) {
                Some((left, right)) => {
                    assert_eq!(left.len() + right.len(), n);
                    let cost = sah(&info, &left) + sah(&info, &right);
                    assert!((cost - naive).abs() <= 1e-5 * naive, "n {n}: {cost} vs {naive}");
                }
                None => assert!(n <= LEAF_MAX, "n {n}: a set over LEAF_MAX was not split"),
            }
        }
    }
}
