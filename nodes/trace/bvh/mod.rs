//! A bounding volume hierarchy over triangles, built bottom up by locally-ordered
//! clustering with reinsertion (`build.rs`, through the `obvhs` crate), collapsed to eight
//! children per node, and traversed front to back with the watertight ray-triangle test of
//! Woop, Benthin and Wald 2013 ("Watertight Ray/Triangle Intersection", JCGT 2(1)).
//!
//! Everything is f32: the triangles are copied into BVH order so a leaf's triangles are
//! contiguous in memory, and traversal allocates nothing.

mod build;
mod lanes;
mod pair;
mod slots;
#[cfg(test)]
mod tests;
mod traverse;
mod wide;

#[cfg(target_arch = "x86_64")]
pub use lanes::Avx;
pub use lanes::{Slab, Sse, Tri4};
pub use pair::{Segment, TraceStacks};
pub use traverse::{intersect_triangle, RayPre};
pub(crate) use traverse::{sheared_test, tri_test};
pub use wide::Node8;

use super::sampling::{cross, sub, V3};

/// Children per node of the 8-wide tree.
pub const W: usize = 8;

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
    /// The same tree collapsed to 8 children per node, filled by `widen` (called by
    /// `build`; the queries traverse it when it is not empty, the binary tree otherwise).
    pub wide: Vec<Node8>,
    /// The 8-wide tree's leaves, four triangles each in structure of arrays.
    pub wide_tris: Vec<Tri4>,
    /// When set, the two-ray queries (`intersect_occluded`, `intersect_pair`) trace their
    /// rays one after the other instead of interleaved (same answers; to measure what the
    /// interleaving buys).
    pub one_at_a_time: bool,
    /// Whether the 8-wide walk asks the cache for a node's data as soon as it picks the
    /// node (set by `widen` when the tree outgrows `PREFETCH_BYTES`: on a small tree, which
    /// stays in the first-level cache, the prefetches only cost instructions).
    pub prefetch: bool,
}

/// The 8-wide tree size (nodes and leaves) from which the walk prefetches.
pub const PREFETCH_BYTES: usize = 256 << 10;

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

impl Hit {
    /// Its fields' bits (distance, triangle, barycentrics), for tests that compare hits
    /// exactly.
    #[cfg(test)]
    pub(crate) fn bits(self) -> [u32; 4] {
        [
            self.t.to_bits(),
            self.prim,
            self.u.to_bits(),
            self.v.to_bits(),
        ]
    }
}

impl Bvh {
    /// Collapses the tree to 8 children per node for the queries to traverse (left empty
    /// when the leaves cannot be encoded: 2^28 triangles or more). `build` calls it.
    pub fn widen(&mut self) {
        (self.wide, self.wide_tris) = wide::collapse(self);
        let bytes =
            std::mem::size_of_val(&self.wide[..]) + std::mem::size_of_val(&self.wide_tris[..]);
        self.prefetch = bytes >= PREFETCH_BYTES;
    }

    /// Drops the 8-wide tree so that the queries traverse the binary one (to compare the
    /// two; `build` makes both).
    pub fn narrow(&mut self) {
        self.wide = Vec::new();
        self.wide_tris = Vec::new();
    }

    /// Bounds of the whole scene.
    pub fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds)
    }
}

/// The (unnormalised) geometric normal `(b - a) x (c - a)` of a triangle.
#[inline]
pub fn triangle_normal(t: &[V3; 3]) -> V3 {
    cross(sub(t[1], t[0]), sub(t[2], t[0]))
}
