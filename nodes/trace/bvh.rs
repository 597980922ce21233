//! A bounding volume hierarchy over triangles, built top-down with the binned surface area
//! heuristic (Wald 2007, "On fast Construction of SAH-based Bounding Volume Hierarchies"),
//! subtrees built in parallel with rayon, and traversed front to back with the watertight
//! ray-triangle test of Woop, Benthin and Wald 2013 ("Watertight Ray/Triangle
//! Intersection", JCGT 2(1)).
//!
//! Everything is f32: the triangles are copied into BVH order so a leaf's triangles are
//! contiguous in memory, and traversal allocates nothing.

use super::sampling::{cross, sub, V3};

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: V3,
    /// Upper corner.
    pub max: V3,
}

impl Aabb {
    /// The empty box (grows from nothing).
    pub const EMPTY: Aabb = Aabb {
        min: [f32::INFINITY; 3],
        max: [f32::NEG_INFINITY; 3],
    };

    /// Grows the box to hold point `p`.
    #[inline]
    pub fn grow(&mut self, p: V3) {
        for ((lo, hi), x) in self.min.iter_mut().zip(self.max.iter_mut()).zip(p) {
            *lo = lo.min(x);
            *hi = hi.max(x);
        }
    }

    /// The union of two boxes.
    #[inline]
    pub fn union(&self, o: &Aabb) -> Aabb {
        let mut r = *self;
        for k in 0..3 {
            r.min[k] = r.min[k].min(o.min[k]);
            r.max[k] = r.max[k].max(o.max[k]);
        }
        r
    }

    /// Half the surface area (the SAH only needs ratios); 0 for an empty box.
    #[inline]
    pub fn half_area(&self) -> f32 {
        let d = sub(self.max, self.min);
        if d[0] < 0.0 {
            return 0.0;
        }
        d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
    }
}

/// A flattened BVH node: a leaf when `count > 0` (triangles `first..first+count`), otherwise
/// an interior node whose children are `first` and `first + 1`.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct BvhNode {
    /// Bounds of everything below.
    pub bounds: Aabb,
    /// First triangle (leaf) or left child (interior).
    pub first: u32,
    /// Number of triangles; 0 for interior nodes.
    pub count: u32,
}

/// A triangle BVH. `tris` holds the triangles in BVH order; `prim[i]` is the caller's index
/// of `tris[i]`.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// Nodes, root first.
    pub nodes: Vec<BvhNode>,
    /// Triangle corners in BVH order.
    pub tris: Vec<[V3; 3]>,
    /// Original index of each triangle in `tris`.
    pub prim: Vec<u32>,
}

/// The closest hit along a ray.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Caller's triangle index.
    pub prim: u32,
    /// Barycentric weight of the second corner.
    pub u: f32,
    /// Barycentric weight of the third corner.
    pub v: f32,
}

/// Per-ray constants of the watertight test (Woop et al. 2013, section 3): the dominant
/// axis `kz`, the permuted axes and the shear that maps the ray to +z.
#[derive(Clone, Copy, Debug)]
pub struct RayPre {
    org: V3,
    inv: V3,
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f32,
    sy: f32,
    sz: f32,
}

impl RayPre {
    /// Precomputes the ray `org + t dir`.
    #[inline]
    pub fn new(org: V3, dir: V3) -> RayPre {
        let a = [dir[0].abs(), dir[1].abs(), dir[2].abs()];
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
        RayPre {
            org,
            inv: [1.0 / dir[0], 1.0 / dir[1], 1.0 / dir[2]],
            kx,
            ky,
            kz,
            sx: dir[kx] / dir[kz],
            sy: dir[ky] / dir[kz],
            sz: 1.0 / dir[kz],
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

/// The test with the axis permutation fixed at compile time (no indexed loads).
#[inline(always)]
fn tri_test<const KX: usize, const KY: usize, const KZ: usize>(
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
    let az = r.sz * a[KZ];
    let bz = r.sz * b[KZ];
    let cz = r.sz * c[KZ];
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

const LEAF_MAX: usize = 4;
const BINS: usize = 16;
const PAR_THRESHOLD: usize = 4096;

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

fn join_children(info: &[PrimInfo], bounds: Aabb, left: Vec<u32>, right: Vec<u32>) -> BuildNode {
    let (l, r) = if left.len() + right.len() > PAR_THRESHOLD {
        rayon::join(|| build_rec(info, left), || build_rec(info, right))
    } else {
        (build_rec(info, left), build_rec(info, right))
    };
    BuildNode::Inner(bounds, Box::new(l), Box::new(r))
}

impl Bvh {
    /// Builds the BVH over `tris` (any order; degenerate triangles are kept and never hit).
    pub fn build(tris: &[[V3; 3]]) -> Bvh {
        let info: Vec<PrimInfo> = tris
            .iter()
            .map(|t| {
                let mut b = Aabb::EMPTY;
                for p in t {
                    b.grow(*p);
                }
                // The vertex centroid (not the box centre) tells apart the two halves of
                // a quad, whose boxes coincide.
                PrimInfo {
                    bounds: b,
                    centroid: [
                        (t[0][0] + t[1][0] + t[2][0]) / 3.0,
                        (t[0][1] + t[1][1] + t[2][1]) / 3.0,
                        (t[0][2] + t[1][2] + t[2][2]) / 3.0,
                    ],
                }
            })
            .collect();
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

    /// Bounds of the whole scene.
    pub fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds)
    }

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
    fn traverse<const ANY: bool>(&self, org: V3, dir: V3, tmax: f32) -> Option<Hit> {
        if self.nodes.is_empty() {
            return None;
        }
        let r = RayPre::new(org, dir);
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
        let r = *r;
        let mut best: Option<Hit> = None;
        let mut tmax = tmax;
        // Stack of (node, entry distance): a popped node is skipped once a closer hit has
        // been found than its entry distance.
        let mut stack = [(0u32, 0.0f32); 96];
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

/// The (unnormalised) geometric normal `(b - a) x (c - a)` of a triangle.
#[inline]
pub fn triangle_normal(t: &[V3; 3]) -> V3 {
    cross(sub(t[1], t[0]), sub(t[2], t[0]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nodes::trace::sampling::{normalize, Pcg32};

    fn random_tris(n: usize, seed: u64) -> Vec<[V3; 3]> {
        let mut r = Pcg32::new(seed, 1);
        (0..n)
            .map(|_| {
                let c = [r.next_f32() * 4.0, r.next_f32() * 4.0, r.next_f32() * 4.0];
                let mut t = [[0.0; 3]; 3];
                for p in &mut t {
                    for k in 0..3 {
                        p[k] = c[k] + (r.next_f32() - 0.5) * 0.6;
                    }
                }
                t
            })
            .collect()
    }

    fn brute(tris: &[[V3; 3]], org: V3, dir: V3) -> Option<(f32, u32)> {
        let r = RayPre::new(org, dir);
        let mut best = None;
        let mut tmax = f32::INFINITY;
        for (i, t) in tris.iter().enumerate() {
            if let Some((th, _, _)) = intersect_triangle(&r, t, tmax) {
                tmax = th;
                best = Some((th, i as u32));
            }
        }
        best
    }

    #[test]
    fn bvh_agrees_with_brute_force() {
        let tris = random_tris(5000, 7);
        let bvh = Bvh::build(&tris);
        assert_eq!(bvh.tris.len(), tris.len());
        let mut r = Pcg32::new(9, 3);
        let mut hits = 0;
        for _ in 0..2000 {
            let org = [r.next_f32() * 6.0 - 1.0, r.next_f32() * 6.0 - 1.0, -2.0];
            let dir = normalize([r.next_f32() - 0.5, r.next_f32() - 0.5, 1.0]);
            let a = bvh
                .intersect(org, dir, f32::INFINITY)
                .map(|h| (h.t, h.prim));
            let b = brute(&tris, org, dir);
            assert_eq!(a.map(|x| x.1), b.map(|x| x.1));
            if let (Some(a), Some(b)) = (a, b) {
                assert_eq!(a.0, b.0);
                hits += 1;
            }
            assert_eq!(
                bvh.occluded(org, dir, f32::INFINITY),
                b.is_some(),
                "any-hit disagrees"
            );
        }
        assert!(hits > 500);
    }

    #[test]
    fn watertight_on_shared_edges_and_vertices() {
        // A fan of triangles around the origin; rays aimed exactly at the shared vertex and
        // along shared edges must hit exactly one or two of them, never slip through.
        let k = 12;
        let mut tris = Vec::new();
        for i in 0..k {
            let a0 = i as f32 / k as f32 * std::f32::consts::TAU;
            let a1 = (i + 1) as f32 / k as f32 * std::f32::consts::TAU;
            tris.push([
                [0.0, 0.0, 0.0],
                [a0.cos(), a0.sin(), 0.0],
                [a1.cos(), a1.sin(), 0.0],
            ]);
        }
        let bvh = Bvh::build(&tris);
        let mut r = Pcg32::new(5, 5);
        for i in 0..2000 {
            // Points on the edges (rays through them) and the centre.
            let e = i % k;
            let a0 = e as f32 / k as f32 * std::f32::consts::TAU;
            let s = if i % 7 == 0 { 0.0 } else { r.next_f32() * 0.9 };
            let target = [s * a0.cos(), s * a0.sin(), 0.0];
            let org = [r.next_f32() - 0.5, r.next_f32() - 0.5, 1.0 + r.next_f32()];
            let dir = normalize(sub(target, org));
            assert!(
                bvh.intersect(org, dir, f32::INFINITY).is_some(),
                "ray {i} slipped through the mesh"
            );
        }
    }

    #[test]
    fn empty_box_is_the_union_identity() {
        let b = Aabb {
            min: [0.0, 1.0, 2.0],
            max: [1.0, 2.0, 3.0],
        };
        assert_eq!(Aabb::EMPTY.union(&b), b);
        assert_eq!(b.union(&Aabb::EMPTY), b);
        assert_eq!(Aabb::EMPTY.union(&Aabb::EMPTY).half_area(), 0.0);
    }

    #[test]
    fn parallel_build_matches_counts() {
        let tris = random_tris(20_000, 11);
        let bvh = Bvh::build(&tris);
        let mut seen = vec![false; tris.len()];
        for &p in &bvh.prim {
            assert!(!seen[p as usize]);
            seen[p as usize] = true;
        }
        assert!(seen.iter().all(|&s| s));
        // Every leaf's triangles lie inside its box.
        for n in bvh.nodes.iter().filter(|n| n.count > 0) {
            for t in &bvh.tris[n.first as usize..(n.first + n.count) as usize] {
                for p in t {
                    for (k, x) in p.iter().enumerate() {
                        assert!(*x >= n.bounds.min[k] && *x <= n.bounds.max[k]);
                    }
                }
            }
        }
    }
}
