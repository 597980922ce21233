use super::*;
use crate::sampling::{normalize, Pcg32};

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
    let tris = fan(k);
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
fn large_build_holds_every_triangle_once() {
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

/// The 8-wide tree holds every triangle exactly once, each leaf's triangles inside the
/// box its parent stores for it, and answers every query as the binary tree does (same
/// triangle, same distance) for closest and any hit, rays starting inside and outside.
#[test]
#[allow(clippy::needless_range_loop)] // lanes index several arrays in step
fn wide_tree_matches_binary_tree() {
    let tris = random_tris(20_000, 13);
    let bvh = Bvh::build(&tris);
    assert!(!bvh.wide.is_empty());
    let mut binary = bvh.clone();
    binary.narrow();
    let mut seen = vec![0u32; bvh.tris.len()];
    let mut leaves_seen = vec![0u32; bvh.wide_tris.len()];
    let mut nodes_seen = vec![0u32; bvh.wide.len()];
    nodes_seen[0] = 1;
    for n in &bvh.wide {
        for l in 0..W {
            let c = n.child[l];
            if c == u32::MAX {
                // An unused lane's box is empty, so no ray enters it.
                assert!((0..3).all(|k| n.min[k][l] > n.max[k][l]));
                continue;
            }
            if c & wide::LEAF != 0 {
                let q = &bvh.wide_tris[((c & !wide::LEAF) >> 3) as usize];
                leaves_seen[((c & !wide::LEAF) >> 3) as usize] += 1;
                for i in 0..(c & 7) as usize {
                    // Lane i holds the caller's triangle q.prim[i], corner for corner.
                    let p = q.prim[i] as usize;
                    seen[p] += 1;
                    assert_eq!(q.get(i), tris[p]);
                    for p in &q.get(i) {
                        for (k, x) in p.iter().enumerate() {
                            assert!(*x >= n.min[k][l] && *x <= n.max[k][l]);
                        }
                    }
                }
            } else {
                nodes_seen[c as usize] += 1;
            }
        }
    }
    assert!(
        seen.iter().all(|&s| s == 1),
        "a triangle missing or repeated"
    );
    assert!(
        nodes_seen.iter().all(|&s| s == 1),
        "a node unreachable or shared"
    );
    assert!(
        leaves_seen.iter().all(|&s| s == 1),
        "a leaf unreachable or shared"
    );
    let mut r = Pcg32::new(21, 5);
    for i in 0..4000 {
        let org = if i % 2 == 0 {
            [r.next_f32() * 6.0 - 1.0, r.next_f32() * 6.0 - 1.0, -2.0]
        } else {
            [r.next_f32() * 4.0, r.next_f32() * 4.0, r.next_f32() * 4.0]
        };
        let dir = normalize([r.next_f32() - 0.5, r.next_f32() - 0.5, r.next_f32() - 0.3]);
        let a = bvh.intersect(org, dir, 3.0).map(|h| (h.t, h.prim));
        let b = binary.intersect(org, dir, 3.0).map(|h| (h.t, h.prim));
        assert_eq!(a, b);
        assert_eq!(bvh.occluded(org, dir, 3.0), b.is_some());
    }
}

/// Rays through the shared vertex and edges of a fan (where the watertight test falls back
/// to double precision, a lane at a time in the 8-wide tree) and grazing rays get the same
/// distance from the 8-wide tree's four-lane tests as from the binary tree, never slip
/// through, and the reported triangle's own scalar test gives that hit.
#[test]
fn wide_tree_matches_binary_tree_on_shared_edges() {
    let k = 12;
    let tris = fan(k);
    let bvh = Bvh::build(&tris);
    assert!(!bvh.wide.is_empty());
    let mut binary = bvh.clone();
    binary.narrow();
    let mut r = Pcg32::new(5, 7);
    for i in 0..3000 {
        let e = i % k;
        let a0 = e as f32 / k as f32 * std::f32::consts::TAU;
        let s = if i % 7 == 0 { 0.0 } else { r.next_f32() * 1.2 };
        let target = [s * a0.cos(), s * a0.sin(), 0.0];
        // Every third ray grazes the plane (direction nearly in it).
        let h = if i % 3 == 0 { 1e-3 } else { 1.0 + r.next_f32() };
        let org = [r.next_f32() * 4.0 - 2.0, r.next_f32() * 4.0 - 2.0, h];
        let dir = normalize(sub(target, org));
        let a = bvh.intersect(org, dir, 10.0);
        let b = binary.intersect(org, dir, 10.0);
        // Same distance; on a tie (the shared vertex or an edge) either triangle may be
        // reported (their distances, computed from different corners, can differ in the
        // last bit), so the reported one is checked to be hit there, with those
        // barycentrics.
        assert_eq!(a.is_some(), b.is_some(), "ray {i}");
        if let (Some(a), Some(b)) = (a, b) {
            assert!(
                (a.t - b.t).abs() <= 1e-6 * b.t,
                "ray {i}: {} against {}",
                a.t,
                b.t
            );
        }
        if let Some(h) = a {
            let own = intersect_triangle(&RayPre::new(org, dir), &tris[h.prim as usize], 10.0);
            assert_eq!(own, Some((h.t, h.u, h.v)), "ray {i}");
        }
        if s < 0.9 {
            assert!(a.is_some(), "ray {i} slipped through the fan");
        }
        assert_eq!(bvh.occluded(org, dir, 10.0), b.is_some());
    }
}

/// `k` triangles around the origin in the z = 0 plane, sharing the centre and their edges.
/// Two rays traced interleaved (`intersect_occluded`, `intersect_pair`) get bit for bit
/// the answers of two single-ray queries (triangle, distance, barycentrics), and those are
/// brute force's; the pairs mix rays that start inside and outside the mesh, miss, and hit
/// at different depths (so one ray of a pair finishes first), and include rays through the
/// shared vertex of a fan (the scalar fallback of the four-lane test).
#[test]
fn interleaved_pairs_match_single_queries() {
    let mut tris = random_tris(5000, 31);
    tris.extend(fan(8));
    let mut bvh = Bvh::build(&tris);
    assert!(!bvh.wide.is_empty());
    // The same answers whether or not the walk prefetches the nodes it picks.
    for prefetch in [false, true] {
        bvh.prefetch = prefetch;
        pairs_match_single_queries(&bvh, &tris);
    }
}

fn pairs_match_single_queries(bvh: &Bvh, tris: &[[V3; 3]]) {
    let mut r = Pcg32::new(17, 9);
    let mut ray = |i: usize| {
        let org = if i.is_multiple_of(3) {
            [r.next_f32() * 4.0, r.next_f32() * 4.0, r.next_f32() * 4.0]
        } else {
            [r.next_f32() * 6.0 - 1.0, r.next_f32() * 6.0 - 1.0, -2.0]
        };
        let dir = if i.is_multiple_of(5) {
            // Through the fan's centre (on its shared vertex).
            normalize(sub([0.0, 0.0, 0.0], org))
        } else {
            normalize([r.next_f32() - 0.5, r.next_f32() - 0.5, r.next_f32() - 0.3])
        };
        let tmax = if i.is_multiple_of(4) {
            1.5
        } else {
            f32::INFINITY
        };
        (org, dir, tmax)
    };
    let key = |h: Option<Hit>| h.map(|h| (h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits()));
    let (mut hits, mut blocked) = (0, 0);
    let mut st = TraceStacks::new();
    for i in 0..3000 {
        let (a, b) = (ray(2 * i), ray(2 * i + 1));
        let single_a = bvh.intersect(a.0, a.1, a.2);
        let single_b = bvh.intersect(b.0, b.1, b.2);
        let (pa, pb) = bvh.intersect_pair(a, b);
        assert_eq!(key(pa), key(single_a), "pair {i}, first ray");
        assert_eq!(key(pb), key(single_b), "pair {i}, second ray");
        let (qa, occ) = bvh.intersect_occluded(a, b);
        assert_eq!(
            key(qa),
            key(single_a),
            "pair {i}, closest hit beside a shadow ray"
        );
        assert_eq!(occ, bvh.occluded(b.0, b.1, b.2), "pair {i}, shadow ray");
        // The inline forms on the caller's stacks give the same answers.
        let single_in = bvh.single_in::<false, _>(&mut st, a);
        assert_eq!(
            key(single_in),
            key(single_a),
            "pair {i}, inline closest hit"
        );
        let occ_a = bvh.occluded(a.0, a.1, a.2);
        assert_eq!(
            bvh.single_in::<true, _>(&mut st, b).is_some(),
            occ,
            "pair {i}, inline shadow ray"
        );
        assert_eq!(
            bvh.occluded_pair_in(&mut st, a, b),
            (occ_a, occ),
            "pair {i}, shadow pair"
        );
        // Brute force over the caller's triangles agrees on triangle and distance, except
        // through the fan's shared vertex: there the fan's triangles tie, the visiting
        // order picks one, and each computes the distance with its own round-off.
        let brute_b = brute(tris, b.0, b.1).filter(|x| x.0 < b.2);
        if (2 * i + 1).is_multiple_of(5) {
            let (t, tb) = (pb.map(|h| h.t), brute_b.map(|x| x.0));
            assert_eq!(t.is_some(), tb.is_some(), "pair {i}");
            if let (Some(t), Some(tb)) = (t, tb) {
                assert!((t - tb).abs() <= 1e-5 * tb, "pair {i}: {t} vs {tb}");
            }
        } else {
            assert_eq!(pb.map(|h| (h.t, h.prim)), brute_b, "pair {i}");
        }
        assert_eq!(occ, brute_b.is_some());
        hits += single_a.is_some() as usize;
        blocked += occ as usize;
    }
    // Both outcomes occur often enough for the pairs to finish in either order.
    assert!(
        hits > 300 && hits < 2900 && blocked > 300 && blocked < 2900,
        "{hits} {blocked}"
    );
}

fn fan(k: usize) -> Vec<[[f32; 3]; 3]> {
    (0..k)
        .map(|i| {
            let a0 = i as f32 / k as f32 * std::f32::consts::TAU;
            let a1 = (i + 1) as f32 / k as f32 * std::f32::consts::TAU;
            [
                [0.0, 0.0, 0.0],
                [a0.cos(), a0.sin(), 0.0],
                [a1.cos(), a1.sin(), 0.0],
            ]
        })
        .collect()
}

/// obvhs builds on every core (its `parallel` feature): the tree must not depend on the
/// thread count, or images would (ties at equal distance go to the first triangle found).
/// 120k triangles, past obvhs's 100k threshold for its parallel Morton sort.
#[test]
fn the_tree_does_not_depend_on_the_thread_count() {
    let tris = random_tris(120_000, 11);
    let build = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        pool.install(|| Bvh::build(&tris))
    };
    let (one, four) = (build(1), build(4));
    assert_eq!(one.prim, four.prim);
    assert_eq!(one.nodes.len(), four.nodes.len());
    assert!(one
        .nodes
        .iter()
        .zip(&four.nodes)
        .all(|(a, b)| (a.first, a.count) == (b.first, b.count)
            && a.bounds.min == b.bounds.min
            && a.bounds.max == b.bounds.max));
}

/// `Avx`'s 256-bit box test gives `Sse`'s mask and entry distances bit for bit: on every
/// node of a tree over random triangles, for random rays, rays along the axes (zero
/// direction components: `0 * inf` is NaN in some lanes) and rays starting on box faces.
#[cfg(target_arch = "x86_64")]
#[test]
fn avx_box_test_is_the_sse_one() {
    use super::lanes::{RayBox, Slab, Sse};
    let Some(avx) = Avx::detect() else {
        eprintln!("this CPU has no AVX: the AVX box test is never used here");
        return;
    };
    let tris = random_tris(3000, 21);
    let bvh = Bvh::build(&tris);
    assert!(!bvh.wide.is_empty());
    let mut r = Pcg32::new(5, 8);
    let mut compared = 0;
    let mut entered = 0;
    for q in 0..600 {
        let n = &bvh.wide[q % bvh.wide.len()];
        let org = match q % 3 {
            0 => [r.next_f32() * 4.0, r.next_f32() * 4.0, r.next_f32() * 4.0],
            // On a face of the node's first box.
            1 => [n.min[0][0], n.min[1][0] + 0.01, n.max[2][0]],
            _ => [-1.0, 2.0, 2.0],
        };
        let dir = match q % 4 {
            0 => [1.0, 0.0, 0.0],
            1 => [0.0, -1.0, 0.0],
            _ => normalize([r.next_f32() - 0.5, r.next_f32() - 0.5, r.next_f32() - 0.5]),
        };
        let ray = RayBox::new(&RayPre::new(org, dir));
        for tmax in [f32::INFINITY, 1.0, 0.0] {
            let (ms, ts) = Sse.slab8(&ray, &n.min, &n.max, tmax);
            let (ma, ta) = avx.slab8(&ray, &n.min, &n.max, tmax);
            assert_eq!(ms, ma, "node {q}, ray {org:?} {dir:?}, tmax {tmax}");
            assert_eq!(ts.map(f32::to_bits), ta.map(f32::to_bits), "node {q}");
            compared += 1;
            entered += ms.count_ones();
        }
    }
    assert!(
        compared == 1800 && entered > 500,
        "{compared} tests, {entered} boxes entered"
    );
}
