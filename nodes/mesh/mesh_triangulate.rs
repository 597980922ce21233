//! `mesh_triangulate`: splits polygons into triangles by ear clipping (Meisters 1975,
//! "Polygons have ears"; Eberly 2002, "Triangulation by Ear Clipping", Geometric Tools), on
//! the plane of each polygon's Newell normal, so non-convex polygons stay inside their
//! outline. Convex quads are split along their shorter diagonal. Per-corner and per-face data
//! follow.
//!
//! Cost (issue 23: the former clipper rescanned every corner against every corner for each
//! ear, O(n³), so one 100k-corner face hung): the remaining corners form a doubly linked
//! list walked as Mapbox's earcut walks it (after a clip, go on from the corner past the
//! ear's far neighbour), an ear is tested only against the reflex corners (Eberly §2: only a
//! reflex corner can lie inside a candidate ear), found through a uniform grid over the
//! polygon's bounding box, and a clip re-classifies only the ear's two neighbours. A convex
//! polygon takes O(n) ear tests and no point-in-triangle test; a polygon with r reflex
//! corners O(n²) ear tests of O(r) each at worst. A face whose clipping would exceed
//! `MAX_EAR_TESTS` point-in-triangle tests is refused with an error naming the face and its
//! corner count, rather than running for minutes.

use cgnodes_api::prelude::*;
use cgnodes_api::types::vec3;

/// The most point-in-triangle tests spent on one face (about a second of work) before
/// `triangulate_polygon` gives up on it.
pub const MAX_EAR_TESTS: u64 = 300_000_000;

fn newell(p: &[[f64; 3]]) -> [f64; 3] {
    let mut n = [0.0; 3];
    for k in 0..p.len() {
        let a = p[k];
        let b = p[(k + 1) % p.len()];
        n[0] += (a[1] - b[1]) * (a[2] + b[2]);
        n[1] += (a[2] - b[2]) * (a[0] + b[0]);
        n[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    n
}

/// Twice the signed area of the triangle `o, a, b` (positive when counter-clockwise).
fn cross2(o: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    vec3::cross2(vec3::sub2(a, o), vec3::sub2(b, o))
}

/// A uniform grid of corner indices over a bounding box, so an ear test visits only the
/// reflex corners near the candidate triangle. Entries are never removed: a corner that is
/// clipped or turns convex is skipped by the caller's flags.
struct Grid {
    lo: [f64; 2],
    inv: [f64; 2],
    side: usize,
    cells: Vec<Vec<u32>>,
}

impl Grid {
    fn new(q: &[[f64; 2]], expected: usize) -> Grid {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in q {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        // About one reflex corner per cell, at most 512 x 512 cells.
        let side = ((expected as f64).sqrt().ceil() as usize).clamp(1, 512);
        let inv = std::array::from_fn(|k| {
            let w = hi[k] - lo[k];
            if w > 0.0 && w.is_finite() {
                side as f64 / w
            } else {
                0.0
            }
        });
        Grid {
            lo,
            inv,
            side,
            cells: vec![Vec::new(); side * side],
        }
    }
    fn cell(&self, x: f64, k: usize) -> usize {
        let c = (x - self.lo[k]) * self.inv[k];
        // NaN and values left of the box go to 0 (`as` saturates), the right edge to side - 1.
        (c.max(0.0) as usize).min(self.side - 1)
    }
    fn insert(&mut self, p: [f64; 2], i: usize) {
        let (cx, cy) = (self.cell(p[0], 0), self.cell(p[1], 1));
        self.cells[cy * self.side + cx].push(i as u32);
    }
}

/// The ear-clipping state of one polygon: remaining corners as a doubly linked list, which
/// of them are reflex (or flat), the grid of reflex corners, and the work spent.
struct Clipper<'a> {
    q: &'a [[f64; 2]],
    prev: Vec<usize>,
    next: Vec<usize>,
    alive: Vec<bool>,
    reflex: Vec<bool>,
    grid: Grid,
    tests: u64,
    budget: u64,
}

impl Clipper<'_> {
    /// Whether corner `b` is reflex or flat in the current polygon (flat corners are treated
    /// as reflex, as Eberly advises, so they block ears and are never clipped as ears).
    fn is_reflex(&self, b: usize) -> bool {
        cross2(self.q[self.prev[b]], self.q[b], self.q[self.next[b]]) <= 0.0
    }

    /// Marks `b` reflex or not, entering newly reflex corners into the grid.
    fn set_reflex(&mut self, b: usize) {
        let r = self.is_reflex(b);
        if r && !self.reflex[b] {
            self.grid.insert(self.q[b], b);
        }
        self.reflex[b] = r;
    }

    /// Whether `b` is an ear: convex, with no remaining reflex corner other than the
    /// triangle's own in the closed triangle `prev(b), b, next(b)`.
    fn is_ear(&mut self, b: usize) -> Result<bool, OverBudget> {
        if self.reflex[b] {
            // Counted too: on self-intersecting input whole turns can pass over reflex
            // corners, and the budget must bound those walks as well.
            self.tests += 1;
            return self.within_budget(false);
        }
        let (a, c) = (self.prev[b], self.next[b]);
        let (qa, qb, qc) = (self.q[a], self.q[b], self.q[c]);
        let g = &self.grid;
        let (x0, x1) = (
            g.cell(qa[0].min(qb[0]).min(qc[0]), 0),
            g.cell(qa[0].max(qb[0]).max(qc[0]), 0),
        );
        let (y0, y1) = (
            g.cell(qa[1].min(qb[1]).min(qc[1]), 1),
            g.cell(qa[1].max(qb[1]).max(qc[1]), 1),
        );
        let mut tests = 1;
        let mut inside = false;
        'cells: for y in y0..=y1 {
            for x in x0..=x1 {
                for &o in &g.cells[y * g.side + x] {
                    let o = o as usize;
                    tests += 1;
                    if !self.alive[o] || !self.reflex[o] || o == a || o == b || o == c {
                        continue;
                    }
                    let p = self.q[o];
                    if cross2(qa, qb, p) >= 0.0
                        && cross2(qb, qc, p) >= 0.0
                        && cross2(qc, qa, p) >= 0.0
                    {
                        inside = true;
                        break 'cells;
                    }
                }
            }
        }
        self.tests += tests;
        self.within_budget(!inside)
    }

    /// `Ok(ear)` while the work spent is within the budget, else the error.
    fn within_budget(&self, ear: bool) -> Result<bool, OverBudget> {
        if self.tests > self.budget {
            return Err(OverBudget {
                budget: self.budget,
            });
        }
        Ok(ear)
    }
}

/// A polygon whose ear clipping would cost more than its budget of point-in-triangle tests.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("triangulating it would take more than {budget} point-in-triangle tests; split it first")]
pub struct OverBudget {
    /// The budget of tests.
    pub budget: u64,
}

/// A face of a mesh too costly to triangulate, by index and corner count.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("face {face} ({corners} corners): {source}")]
pub struct FaceTooCostly {
    /// The face's index.
    pub face: usize,
    /// Its corner count.
    pub corners: usize,
    /// The budget it exceeds.
    pub source: OverBudget,
}

/// Triangles (as local corner indices) covering a simple polygon given by its 3-D corners,
/// in the polygon's winding. Degenerate or self-intersecting input still yields `n - 2`
/// triangles (a corner is cut off anyway once no ear is left). Fails only when the polygon
/// would cost more than `MAX_EAR_TESTS` point-in-triangle tests.
pub fn triangulate_polygon(p: &[[f64; 3]]) -> Result<Vec<[usize; 3]>, OverBudget> {
    clip_polygon(p, MAX_EAR_TESTS)
}

/// `triangulate_polygon` with a given budget of point-in-triangle tests.
fn clip_polygon(p: &[[f64; 3]], budget: u64) -> Result<Vec<[usize; 3]>, OverBudget> {
    let n = p.len();
    if n < 3 {
        return Ok(Vec::new());
    }
    if n == 3 {
        return Ok(vec![[0, 1, 2]]);
    }
    // Project onto the coordinate plane most aligned with the normal, keeping the winding
    // counter-clockwise in 2-D.
    let nn = newell(p);
    let ax = (0..3)
        .max_by(|&a, &b| nn[a].abs().total_cmp(&nn[b].abs()))
        .unwrap_or(2);
    let (mut u, mut v) = ((ax + 1) % 3, (ax + 2) % 3);
    if nn[ax] < 0.0 {
        std::mem::swap(&mut u, &mut v);
    }
    let q: Vec<[f64; 2]> = p.iter().map(|x| [x[u], x[v]]).collect();
    let d2 = |a: usize, b: usize| (0..3).map(|k| (p[a][k] - p[b][k]).powi(2)).sum::<f64>();
    if n == 4 {
        let convex = (0..4).all(|k| cross2(q[(k + 3) % 4], q[k], q[(k + 1) % 4]) > 0.0);
        if convex {
            return Ok(if d2(0, 2) <= d2(1, 3) {
                vec![[0, 1, 2], [0, 2, 3]]
            } else {
                vec![[0, 1, 3], [1, 2, 3]]
            });
        }
    }
    let mut s = Clipper {
        q: &q,
        prev: (0..n).map(|i| (i + n - 1) % n).collect(),
        next: (0..n).map(|i| (i + 1) % n).collect(),
        alive: vec![true; n],
        reflex: vec![false; n],
        grid: Grid::new(&q, 0),
        tests: 0,
        budget,
    };
    let reflex: Vec<usize> = (0..n).filter(|&i| s.is_reflex(i)).collect();
    s.grid = Grid::new(&q, reflex.len());
    for &i in &reflex {
        s.set_reflex(i);
    }
    // Walk the ring as Mapbox's earcut does: test the corner under the cursor; after a clip,
    // go on two corners further, so one pass cuts every other corner of a convex run and the
    // triangles stay local (clipping the lowest-index ear each time made a fan whose ever
    // larger triangles each overlapped every grid cell).
    let mut out = Vec::with_capacity(n - 2);
    let (mut left, mut b, mut stop) = (n, 0, 0);
    let mut any = 0;
    while left > 3 {
        let ear = s.is_ear(b)?;
        if !ear {
            b = s.next[b];
            if b != stop {
                continue;
            }
            // A whole turn without an ear (degenerate or self-intersecting input): cut a
            // nearby convex corner, or this one, so the output still has n - 2 triangles.
            for _ in 0..left.min(64) {
                if !s.reflex[b] {
                    break;
                }
                b = s.next[b];
            }
        }
        let (a, c) = (s.prev[b], s.next[b]);
        out.push([a, b, c]);
        s.next[a] = c;
        s.prev[c] = a;
        s.alive[b] = false;
        left -= 1;
        any = a;
        s.set_reflex(a);
        s.set_reflex(c);
        b = s.next[c];
        stop = b;
    }
    // The last three corners, from the lowest index, in the polygon's order.
    let a = any.min(s.next[any]).min(s.prev[any]);
    out.push([a, s.next[a], s.next[s.next[a]]]);
    Ok(out)
}

/// A copy of `mesh` with every face split into triangles; returns the mesh and how many
/// polygons (faces with more than 3 corners) were split. Fails, naming the face and its
/// corner count, on a face too costly to clip (see `MAX_EAR_TESTS`).
pub fn triangulate(mesh: &Mesh) -> Result<(Mesh, usize), FaceTooCostly> {
    triangulate_within(mesh, MAX_EAR_TESTS)
}

/// `triangulate` with a budget of point-in-triangle tests per face.
fn triangulate_within(mesh: &Mesh, budget: u64) -> Result<(Mesh, usize), FaceTooCostly> {
    let starts = mesh.face_starts();
    let mut idx = Vec::new();
    let mut corner_src = Vec::new();
    let mut face_src = Vec::new();
    let mut split = 0;
    for (f, face) in mesh.faces().enumerate() {
        let s = starts[f] as usize;
        if face.len() > 3 {
            split += 1;
        }
        let pts: Vec<[f64; 3]> = face.iter().map(|&v| mesh.positions[v as usize]).collect();
        let tris = clip_polygon(&pts, budget).map_err(|source| FaceTooCostly {
            face: f,
            corners: face.len(),
            source,
        })?;
        for t in tris {
            for k in t {
                idx.push(face[k]);
                corner_src.push(s + k);
            }
            face_src.push(f);
        }
    }
    fn re<T: Clone>(a: &Attribute<T>, c: &[usize], f: &[usize]) -> Attribute<T> {
        let map = match a.domain {
            Domain::Vertex => return a.clone(),
            Domain::Corner => c,
            Domain::Face => f,
        };
        Attribute {
            domain: a.domain,
            values: map.iter().map(|&i| a.values[i].clone()).collect(),
        }
    }
    let mut out = mesh.clone();
    let nt = face_src.len();
    out.set_faces(vec![3; nt], idx);
    let (c, f) = (&corner_src[..], &face_src[..]);
    out.uvs = mesh.uvs.as_ref().map(|a| re(a, c, f));
    out.normals = mesh.normals.as_ref().map(|a| re(a, c, f));
    out.colors = mesh.colors.as_ref().map(|a| re(a, c, f));
    out.attributes = mesh
        .attributes
        .iter()
        .map(|(k, a)| {
            let na = match a {
                AttributeData::Float(a) => AttributeData::Float(re(a, c, f)),
                AttributeData::Vec2(a) => AttributeData::Vec2(re(a, c, f)),
                AttributeData::Vec3(a) => AttributeData::Vec3(re(a, c, f)),
                AttributeData::Int(a) => AttributeData::Int(re(a, c, f)),
            };
            (k.clone(), na)
        })
        .collect();
    Ok((out, split))
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Splits polygon faces into triangles (ear clipping; per-corner data follow).");
    b.add_input::<Mesh>("mesh");
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    if mesh.is_triangle_mesh() {
        ctx.log("already all triangles");
        ctx.set_output("mesh", mesh);
        return Ok(());
    }
    let (out, split) = triangulate(&mesh).map_err(|e| NodeError::invalid("mesh", e.to_string()))?;
    ctx.log(format!(
        "split {split} polygons: {} faces -> {} triangles",
        mesh.num_faces(),
        out.num_faces()
    ));
    ctx.set_output("mesh", out);
    Ok(())
}

/// Registers `mesh_triangulate`.
pub fn register(r: &mut Registry) {
    r.add("mesh_triangulate", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area2(q: &[[f64; 3]], t: [usize; 3]) -> f64 {
        let (a, b, c) = (q[t[0]], q[t[1]], q[t[2]]);
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    }

    #[test]
    fn concave_polygon_stays_inside_and_keeps_area() {
        // An L shape (area 3) whose fan from corner 0 would leave the outline.
        let p = vec![
            [1.0, 1.0, 0.0],
            [1.0, 2.0, 0.0],
            [0.0, 2.0, 0.0],
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 1.0, 0.0],
        ];
        let t = triangulate_polygon(&p).unwrap();
        assert_eq!(t.len(), 4);
        let total: f64 = t.iter().map(|&t| area2(&p, t) / 2.0).sum();
        assert!((total - 3.0).abs() < 1e-12);
        // every triangle is counter-clockwise like the polygon: none folds over
        assert!(t.iter().all(|&t| area2(&p, t) > 0.0));
    }

    #[test]
    fn quads_split_on_the_shorter_diagonal_and_uvs_follow() {
        let p = vec![
            [0.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [4.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
        ];
        let mut m = Mesh::new(p, vec![4], vec![0, 1, 2, 3]).unwrap();
        m.uvs = Some(Attribute {
            domain: Domain::Corner,
            values: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        });
        let (t, split) = triangulate(&m).unwrap();
        assert_eq!(split, 1);
        // diagonal 1-3 (length sqrt 5) is shorter than 0-2 (sqrt 17)
        assert_eq!(t.face_indices(), &[0, 1, 3, 1, 2, 3]);
        assert_eq!(t.uvs.as_ref().unwrap().values[2], [0.0, 1.0]);
        t.check().unwrap();
    }

    /// Twice the polygon's signed area by the shoelace formula.
    fn shoelace2(p: &[[f64; 3]]) -> f64 {
        (0..p.len())
            .map(|k| {
                let (a, b) = (p[k], p[(k + 1) % p.len()]);
                a[0] * b[1] - b[0] * a[1]
            })
            .sum()
    }

    /// The triangles cover the polygon exactly once: n - 2 of them, each corner of a
    /// triangle distinct, none clockwise, and their areas add up to the shoelace area.
    fn assert_valid(p: &[[f64; 3]], t: &[[usize; 3]]) {
        assert_eq!(t.len(), p.len() - 2);
        assert!(t
            .iter()
            .all(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2]));
        assert!(
            t.iter().all(|&t| area2(p, t) > 0.0),
            "a triangle folds over"
        );
        let total: f64 = t.iter().map(|&t| area2(p, t)).sum();
        let want = shoelace2(p);
        assert!(
            (total - want).abs() <= 1e-9 * want.abs(),
            "{total} vs {want}"
        );
    }

    /// A star around the origin: `n` corners alternating between radius 1 and `inner`, so
    /// every other corner is reflex when `inner` is small.
    fn star(n: usize, inner: f64) -> Vec<[f64; 3]> {
        (0..n)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                let r = if k % 2 == 0 { 1.0 } else { inner };
                [r * a.cos(), r * a.sin(), 0.0]
            })
            .collect()
    }

    /// Issue 23: one face with 100k corners hung the O(n³) clipper (and the O(n²) repeated
    /// vertex check of `Mesh::new`). A convex one now goes through the node's path in
    /// milliseconds, as n - 2 triangles covering the polygon.
    #[test]
    fn a_convex_face_with_100k_corners_triangulates() {
        let n = 100_000;
        let p = star(n, 1.0);
        let m = Mesh::new(p.clone(), vec![n as u32], (0..n as u32).collect()).unwrap();
        let (t, split) = triangulate(&m).unwrap();
        assert_eq!(split, 1);
        let tris: Vec<[usize; 3]> = t
            .face_indices()
            .chunks_exact(3)
            .map(|c| [c[0] as usize, c[1] as usize, c[2] as usize])
            .collect();
        assert_valid(&p, &tris);
    }

    /// A 100k-corner circle of radius 100 stored in single precision: rounding turns the
    /// arc into a zigzag with about half its corners reflex. Clipping the lowest corner first
    /// made a fan whose triangles covered the whole grid, past the test budget; walking the
    /// ring keeps ears local, and the result still covers the polygon without folds.
    #[test]
    fn a_rounded_circle_with_100k_corners_triangulates() {
        let n = 100_000;
        let p: Vec<[f64; 3]> = star(n, 1.0)
            .iter()
            .map(|x| {
                [
                    (100.0 * x[0]) as f32 as f64,
                    (100.0 * x[1]) as f32 as f64,
                    0.0,
                ]
            })
            .collect();
        let reflex = (0..n)
            .filter(|&k| cross2_3(p[(k + n - 1) % n], p[k], p[(k + 1) % n]) <= 0.0)
            .count();
        assert!(reflex > n / 10, "{reflex} reflex corners");
        assert_valid(&p, &triangulate_polygon(&p).unwrap());
    }

    fn cross2_3(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
        cross2([a[0], a[1]], [b[0], b[1]], [c[0], c[1]])
    }

    /// A star with 20k corners, half of them reflex, and star-shaped polygons with random
    /// radii: every triangulation is valid (no fold, area kept).
    #[test]
    fn concave_stars_triangulate_validly() {
        let p = star(20_000, 0.3);
        assert_valid(&p, &triangulate_polygon(&p).unwrap());
        // Random star-shaped (hence simple) polygons, from a fixed linear congruential stream.
        let mut seed = 12345u64;
        let mut rnd = || cgnodes_api::rng::lcg_next(&mut seed);
        for _ in 0..300 {
            let n = 4 + (rnd() * 60.0) as usize;
            let p: Vec<[f64; 3]> = (0..n)
                .map(|k| {
                    let a = std::f64::consts::TAU * (k as f64 + 0.8 * rnd()) / n as f64;
                    let r = 0.05 + rnd();
                    [r * a.cos(), r * a.sin(), 0.0]
                })
                .collect();
            assert_valid(&p, &triangulate_polygon(&p).unwrap());
        }
    }

    /// Clockwise input keeps its winding (the projection flips it), and a comb whose teeth
    /// block each other's ears is still valid.
    #[test]
    fn clockwise_and_comb_polygons() {
        let mut p = star(41, 0.5);
        p.reverse();
        let t = triangulate_polygon(&p).unwrap();
        let flipped: Vec<[f64; 3]> = p.iter().map(|x| [x[0], -x[1], 0.0]).collect();
        assert_valid(&flipped, &t);
        // A comb: a base from (0,0) to (2k,0), then k teeth of height 10 walked back to x = 0.
        let k = 200;
        let mut comb = vec![[0.0, 0.0, 0.0], [2.0 * k as f64, 0.0, 0.0]];
        for i in (0..k).rev() {
            let x = 2.0 * i as f64;
            comb.extend([
                [x + 2.0, 10.0, 0.0],
                [x + 1.0, 10.0, 0.0],
                [x + 1.0, 1.0, 0.0],
                [x, 1.0, 0.0],
            ]);
        }
        assert_valid(&comb, &triangulate_polygon(&comb).unwrap());
    }

    /// A self-intersecting figure eight (one lobe wound against the projected normal, so its
    /// corners all look reflex) still gives n - 2 triangles, and a large one is bounded by
    /// the budget instead of walking whole turns for every clip.
    #[test]
    fn self_intersecting_input_terminates() {
        let eight = |n: usize| -> Vec<[f64; 3]> {
            (0..n)
                .map(|k| {
                    let t = std::f64::consts::TAU * k as f64 / n as f64;
                    [
                        t.sin(),
                        (2.0 * t).sin() * if k < n / 2 { 0.5 } else { 0.3 },
                        0.0,
                    ]
                })
                .collect()
        };
        assert_eq!(triangulate_polygon(&eight(200)).unwrap().len(), 198);
        let e = clip_polygon(&eight(20_000), 1_000_000)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("more than 1000000 point-in-triangle tests"),
            "{e}"
        );
    }

    /// Past its budget of point-in-triangle tests a face is refused, and the error names the
    /// face and its corner count.
    #[test]
    fn a_face_over_budget_is_refused_by_index() {
        let tri = [[0.0, 0.0, 5.0], [1.0, 0.0, 5.0], [0.0, 1.0, 5.0]];
        let mut p: Vec<[f64; 3]> = tri.to_vec();
        p.extend(star(400, 0.3));
        let counts = vec![3, 400];
        let m = Mesh::new(p, counts, (0..403).collect()).unwrap();
        let e = triangulate_within(&m, 1000).unwrap_err().to_string();
        assert!(e.starts_with("face 1 (400 corners): triangulating it would take more than 1000 point-in-triangle tests"), "{e}");
        assert!(triangulate_within(&m, MAX_EAR_TESTS).is_ok());
    }
}
