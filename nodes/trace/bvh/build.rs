//! BVH construction: the binary tree is built bottom up by locally-ordered clustering
//! (PLOC: Meister and Bittner 2018, "Parallel Locally-Ordered Clustering for Bounding Volume
//! Hierarchy Construction", IEEE TVCG 24(3)), improved by moving subtrees to where they cost
//! less (Meister and Bittner 2018, "Parallel Reinsertion for Bounding Volume Hierarchy
//! Optimization", Computer Graphics Forum 37(2)), and its leaves collapsed to at most four
//! triangles by the surface area heuristic; all three from the `obvhs` crate. It is then
//! laid out depth first, children of a node side by side, with the triangles copied into
//! tree order, and collapsed to eight children per node (`wide.rs`).
//!
//! Why not top-down SAH: our binned and swept SAH tree (Wald 2007; MacDonald and Booth 1990)
//! had a lower SAH cost on the igea scene than PLOC's, but its rays visited 1.2-1.7x as many
//! nodes and 2.5-4.6x as many leaves, and traced 1.6x slower (docs/path_tracing.md, ninth
//! round): the cost model counts rays that pass through, while most rays of a path tracer
//! start on a surface and end on the next one, where PLOC's compact clusters pay.

use super::{Aabb, Bvh, BvhNode};
use crate::sampling::V3;
use glam::Vec3A;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::ploc::PlocSearchDistance;
use obvhs::BvhBuildParams;
use rayon::prelude::*;

/// The build settings for `n` triangles: obvhs's `slow_build` without its spatial pre-splits
/// (which bought nothing on our scenes), with PLOC's nearest-neighbour search over 6
/// neighbours instead of 24 and a reinsertion share that falls with the scene's size
/// (`reinsertion_ratio`); leaves of at most four triangles (one `Tri4`). Against
/// `slow_build`, in instructions of `cargo bench --bench trace -- --rays` (callgrind): equal
/// on the box (whose small tree needs the pass after the leaf collapse: +18 % without it),
/// igea +0.6 %, four other scans -19 % to 0 %; igea's tree builds in about a third of the
/// time (docs/path_tracing.md).
fn params(n: usize) -> BvhBuildParams {
    BvhBuildParams {
        pre_split: false,
        ploc_search_distance: PlocSearchDistance::Low,
        reinsertion_batch_ratio: reinsertion_ratio(n),
        max_prims_per_leaf: 4,
        ..BvhBuildParams::slow_build()
    }
}

/// The share of the nodes reinserted per pass for `n` triangles: 2048 / n, within 1 % and
/// 20 % (`slow_build`'s share, kept up to about 10k triangles). The binary tree has about
/// 2n nodes, so a large scene's first pass takes about 4096 candidates.
fn reinsertion_ratio(n: usize) -> f32 {
    (2048.0 / n.max(1) as f32).clamp(0.01, 0.2)
}

/// A triangle's box, or, when a corner is not finite (never the case for a `Mesh`, which
/// rejects such positions), a point at `fallback`: the clustering needs finite boxes, and
/// the triangle test never reports a hit on such a triangle anyway.
fn tri_box(t: &[V3; 3], fallback: V3) -> Aabb {
    if t.iter().flatten().all(|x| x.is_finite()) {
        let mut b = Aabb::EMPTY;
        t.iter().for_each(|p| b.grow(*p));
        b
    } else {
        Aabb {
            min: fallback,
            max: fallback,
        }
    }
}

impl Bvh {
    /// Builds the BVH over `tris` (any order; degenerate triangles are kept and never hit),
    /// and its 8-wide form (`widen`), which the queries traverse.
    pub fn build(tris: &[[V3; 3]]) -> Bvh {
        let mut bvh = Bvh::default();
        if tris.is_empty() {
            return bvh;
        }
        let fallback = tris
            .iter()
            .flatten()
            .find(|p| p.iter().all(|x| x.is_finite()))
            .copied()
            .unwrap_or([0.0; 3]);
        let v = |p: V3| Vec3A::new(p[0], p[1], p[2]);
        let boxes: Vec<obvhs::aabb::Aabb> = tris
            .par_iter()
            .map(|t| {
                let b = tri_box(t, fallback);
                obvhs::aabb::Aabb::new(v(b.min), v(b.max))
            })
            .collect();
        let mut build_time = std::time::Duration::ZERO; // obvhs reports its time here
        let b2 = build_bvh2(&boxes, params(tris.len()), &mut build_time);
        // Depth first from the root (obvhs's node 0), a node's two children side by side
        // after it, so that each subtree's triangles are contiguous (`wide::collapse` relies
        // on both).
        let empty = BvhNode {
            bounds: Aabb::EMPTY,
            first: 0,
            count: 0,
        };
        bvh.nodes.push(empty);
        bvh.prim.reserve(tris.len());
        let mut todo = vec![(0usize, 0usize)]; // (obvhs node, our slot)
        while let Some((src, slot)) = todo.pop() {
            let n = &b2.nodes[src];
            let bounds = Aabb {
                min: n.aabb.min.into(),
                max: n.aabb.max.into(),
            };
            if n.prim_count > 0 {
                let first = bvh.prim.len() as u32;
                let ids = &b2.primitive_indices[n.first_index as usize..][..n.prim_count as usize];
                bvh.prim.extend_from_slice(ids);
                bvh.nodes[slot] = BvhNode {
                    bounds,
                    first,
                    count: n.prim_count,
                };
            } else {
                let first = bvh.nodes.len();
                bvh.nodes.push(empty);
                bvh.nodes.push(empty);
                bvh.nodes[slot] = BvhNode {
                    bounds,
                    first: first as u32,
                    count: 0,
                };
                // Left subtree first (popped first), then the right one.
                todo.push((n.first_index as usize + 1, first + 1));
                todo.push((n.first_index as usize, first));
            }
        }
        // The triangles in tree order, copied on every core.
        bvh.tris = bvh.prim.par_iter().map(|&p| tris[p as usize]).collect();
        bvh.widen();
        bvh
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Few, coincident, degenerate and non-finite triangles build a tree that holds each
    /// triangle once, with every node's box holding its children's boxes (what traversal
    /// relies on) and every leaf's box its finite triangles.
    #[test]
    fn small_and_odd_inputs_build_valid_trees() {
        let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let flat = [[2.0, 2.0, 2.0]; 3];
        let bad = [
            [f32::NAN, 0.0, 0.0],
            [1.0, f32::INFINITY, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let cases: Vec<Vec<[V3; 3]>> = vec![
            vec![t],
            vec![t, t],
            vec![t, flat, t],
            vec![t; 9],
            vec![bad, t, flat, bad, t],
            vec![bad],
        ];
        for tris in cases {
            let bvh = Bvh::build(&tris);
            let mut seen = vec![0; tris.len()];
            bvh.prim.iter().for_each(|&p| seen[p as usize] += 1);
            assert!(seen.iter().all(|&s| s == 1), "{seen:?}");
            let inside =
                |a: &Aabb, b: &Aabb| (0..3).all(|k| a.min[k] <= b.min[k] && b.max[k] <= a.max[k]);
            for n in &bvh.nodes {
                if n.count == 0 {
                    let f = n.first as usize;
                    assert!(inside(&n.bounds, &bvh.nodes[f].bounds));
                    assert!(inside(&n.bounds, &bvh.nodes[f + 1].bounds));
                } else {
                    for t in &bvh.tris[n.first as usize..(n.first + n.count) as usize] {
                        let b = tri_box(t, [f32::NAN; 3]);
                        assert!(b.min[0].is_nan() || inside(&n.bounds, &b));
                    }
                }
            }
            assert!(!bvh.wide.is_empty());
            // A ray through the finite triangle finds it (and nothing else is hit).
            let h = bvh.intersect([0.25, 0.25, -1.0], [0.0, 0.0, 1.0], f32::INFINITY);
            let hit = h.map(|h| tris[h.prim as usize]);
            assert_eq!(hit, tris.contains(&t).then_some(t));
        }
    }
}
