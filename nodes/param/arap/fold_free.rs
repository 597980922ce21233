//! The fold-free machinery of the local/global iteration: when the orientation-preserving
//! step is much shorter than the best step, the triangles that block it are stiffened
//! (their Laplacian weights raised), the rings around them re-solved locally with the
//! stiffened weights, and the whole Laplacian refactored when the schedule's triggers fire
//! (`RefactorSchedule`). Stiffened triangles move almost rigidly with their surroundings,
//! so the next step is longer without any triangle flipping.

use super::frames::TriangleFrames;
use super::line_search::Directional;
use super::options::{
    ArapOptions, RefactorSchedule, LOCAL_MAX_FRACTION, MAX_WEIGHT, MIN_STEP, REWEIGHT_FACTOR,
    STEP_SAFETY,
};
use cgnodes_linalg::SpdFactor;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Mat, Par};

/// The fold-free mode's state across iterations: the triangle weights and the counters that
/// drive the refactorization schedule, and the local re-solve's adjacency and scratch.
pub(super) struct FoldFree {
    /// Factor on each triangle's Laplacian weights (1 until it blocks a step).
    pub weights: Vec<f64>,
    /// Stiffenings not yet in the factor.
    pub pending: usize,
    /// Blocked iterations since the last refactorization.
    pub blocked_run: usize,
    /// Times a triangle's weight was raised.
    pub reweighted: usize,
    /// Numeric refactorizations after reweighting.
    pub refactors: usize,
    /// Local stiffened re-solves.
    pub local_solves: usize,
    /// The triangles of each vertex, in compressed rows (`vertex_triangles`).
    adjacency: (Vec<usize>, Vec<u32>),
    /// Rings of vertices a local re-solve adds around its seeds (`ArapOptions::local_rings`).
    rings: usize,
    /// Scratch of `local_resolve`; its `touched` lists the triangles whose direction the last
    /// local re-solve changed.
    pub scratch: LocalScratch,
}

/// Scratch of `local_resolve`, sized for the mesh once.
pub(super) struct LocalScratch {
    /// Per vertex: its ring while the region grows, then its index in the region
    /// (all `u32::MAX` between calls).
    mark: Vec<u32>,
    /// Per triangle: already in `touched` (all `false` between calls).
    seen: Vec<bool>,
    /// The triangles whose direction the last call changed.
    pub touched: Vec<u32>,
}

impl LocalScratch {
    /// Scratch for `n` vertices and `m` triangles.
    pub fn new(n: usize, m: usize) -> LocalScratch {
        LocalScratch {
            mark: vec![u32::MAX; n],
            seen: vec![false; m],
            touched: Vec::new(),
        }
    }
}

/// Why `local_resolve` left the direction as it was.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub(super) enum LocalError {
    /// No blocking triangle has a free vertex.
    #[error("no free vertex to re-solve")]
    NoFreeVertex,
    /// The region is larger than `LocalProblem::max_region`: refactor instead.
    #[error("region of {0} vertices: refactor instead")]
    RegionTooLarge(usize),
    /// The region's system could not be factored.
    #[error("local factorization failed: {0}")]
    Factor(String),
    /// The region's solution is not finite.
    #[error("non-finite local solution")]
    NotFinite,
}

/// What a local stiffened re-solve works on (`local_resolve`).
pub(super) struct LocalProblem<'a> {
    /// The triangles' frames and cotangents.
    pub frames: &'a TriangleFrames,
    /// Each triangle's stiffening factor on its Laplacian weights.
    pub weights: &'a [f64],
    /// Each triangle's largest step before it reaches its area floor.
    pub limits: &'a [f64],
    /// The step the direction's model asks for; triangles with
    /// `STEP_SAFETY * limit < best_step` seed the region.
    pub best_step: f64,
    /// Rings of vertices added around the seeds.
    pub rings: usize,
    /// Largest region re-solved (vertices).
    pub max_region: usize,
    /// A vertex's row in the global factor's elimination order, also its row in `gradient`
    /// (`u32::MAX` when fixed).
    pub row_of: &'a [u32],
    /// `∇E` on the free vertices, in elimination order.
    pub gradient: &'a Mat<f64>,
    /// Each vertex's triangles, in compressed rows.
    pub adjacency: &'a (Vec<usize>, Vec<u32>),
}

impl FoldFree {
    /// Unit weights for the `m` triangles over `n` vertices; empty when `opts.injective` is
    /// off (and no adjacency when `opts.local_rings` is 0).
    pub fn new(n: usize, frames: &TriangleFrames, opts: &ArapOptions) -> FoldFree {
        let m = frames.len();
        FoldFree {
            weights: vec![1.0; if opts.injective { m } else { 0 }],
            pending: 0,
            blocked_run: 0,
            reweighted: 0,
            refactors: 0,
            local_solves: 0,
            scratch: if opts.injective {
                LocalScratch::new(n, m)
            } else {
                LocalScratch::new(0, 0)
            },
            adjacency: if opts.injective && opts.local_rings > 0 {
                cgnodes_api::types::Topology::vertex_triangles(n, &frames.triangles)
            } else {
                (Vec::new(), Vec::new())
            },
            rings: opts.local_rings,
        }
    }

    /// Stiffens the triangles that would flip before `best_step` (`reweight`), counting them
    /// as pending for the factor.
    #[inline]
    pub fn stiffen(&mut self, limits: &[f64], best_step: f64) {
        let changed = reweight(limits, best_step, &mut self.weights);
        self.pending += changed;
        self.reweighted += changed;
    }

    /// Whether one of the schedule's triggers asks for a refactorization, among `m`
    /// triangles, with the search direction's `dir`.
    #[inline]
    pub fn refactor_due(&self, sched: &RefactorSchedule, m: usize, dir: &Directional) -> bool {
        self.blocked_run >= sched.blocked_run
            || self.pending as f64 >= sched.growth * m as f64
            || dir.squeezed
            || dir.max_step < MIN_STEP
    }

    /// `local_resolve` with this state's weights, adjacency and scratch (`scratch.touched`
    /// receives the triangles whose direction changed), the region capped at
    /// `LOCAL_MAX_FRACTION` of the free vertices.
    pub fn local_resolve(
        &mut self,
        frames: &TriangleFrames,
        limits: &[f64],
        best_step: f64,
        row_of: &[u32],
        gradient: &Mat<f64>,
        d: &mut [[f64; 2]],
    ) -> Result<usize, LocalError> {
        let problem = LocalProblem {
            frames,
            weights: &self.weights,
            limits,
            best_step,
            rings: self.rings,
            max_region: (LOCAL_MAX_FRACTION * gradient.nrows() as f64) as usize,
            row_of,
            gradient,
            adjacency: &self.adjacency,
        };
        local_resolve(&problem, &mut self.scratch, d)
    }
}

/// Local stiffened re-solve of a blocked step: on the vertices within `p.rings` rings of the
/// triangles that would reach their area floor before `p.best_step`, replaces `d` by the
/// minimizer of the global step's model `g·δ + ½ δᵀ Δ_W δ` (stiffened weights `Δ_W`) with `δ`
/// held at `d` everywhere else, a small Dirichlet problem factored on the spot, its vertices
/// numbered in the global factor's elimination order (`p.row_of`), which fills no more than
/// the global factor does there and spares computing an ordering. The blocking triangles then
/// move almost rigidly with their surroundings instead of cutting the step for the whole
/// mesh, without refactoring the global Laplacian. Returns the number of vertices re-solved,
/// or an error when there is nothing to re-solve or the region holds more than
/// `p.max_region` vertices (see `LOCAL_MAX_FRACTION`: a refactorization of the whole
/// Laplacian then costs about as much and does better), `d` then unchanged;
/// `scratch.touched` receives the triangles whose direction changed.
pub(super) fn local_resolve(
    p: &LocalProblem,
    scratch: &mut LocalScratch,
    d: &mut [[f64; 2]],
) -> Result<usize, LocalError> {
    let region = grow_region(p, &mut scratch.mark);
    // numbered in the global factor's elimination order, a fill-reducing order for the region
    for (k, &v) in region.iter().enumerate() {
        scratch.mark[v as usize] = k as u32;
    }
    scratch.touched.clear();
    let r = region.len();
    let result = if r == 0 {
        Err(LocalError::NoFreeVertex)
    } else if r > p.max_region {
        Err(LocalError::RegionTooLarge(r))
    } else {
        solve_region(p, &region, scratch, d)
    };
    for &v in &region {
        scratch.mark[v as usize] = u32::MAX;
    }
    for &t in scratch.touched.iter() {
        scratch.seen[t as usize] = false;
    }
    result
}

/// The free vertices of the blocking triangles (ring 0) and `p.rings` rings around them,
/// sorted by their row in the global factor. `mark` holds each one's ring on return.
fn grow_region(p: &LocalProblem, mark: &mut [u32]) -> Vec<u32> {
    let tris = &p.frames.triangles;
    let (vt_start, vt) = (&p.adjacency.0, &p.adjacency.1);
    let mut region: Vec<u32> = Vec::new();
    for (tri, &lim) in tris.iter().zip(p.limits) {
        if STEP_SAFETY * lim < p.best_step {
            for &v in tri {
                if mark[v as usize] == u32::MAX && p.row_of[v as usize] != u32::MAX {
                    mark[v as usize] = 0;
                    region.push(v);
                }
            }
        }
    }
    let mut ring_start = 0;
    for ring in 0..p.rings as u32 {
        let ring_end = region.len();
        for k in ring_start..ring_end {
            let v = region[k] as usize;
            for &t in &vt[vt_start[v]..vt_start[v + 1]] {
                for &u in &tris[t as usize] {
                    if mark[u as usize] == u32::MAX && p.row_of[u as usize] != u32::MAX {
                        mark[u as usize] = ring + 1;
                        region.push(u);
                    }
                }
            }
        }
        ring_start = ring_end;
    }
    region.sort_unstable_by_key(|&v| p.row_of[v as usize]);
    region
}

/// Assembles, factors and solves the region's Dirichlet problem (`scratch.mark`: each
/// region vertex's index, `u32::MAX` outside) and writes its solution into `d`.
fn solve_region(
    p: &LocalProblem,
    region: &[u32],
    scratch: &mut LocalScratch,
    d: &mut [[f64; 2]],
) -> Result<usize, LocalError> {
    let r = region.len();
    let (upper, mut rhs) = region_system(p, region, scratch, d);
    let f = SpdFactor::from_upper_in_order(upper, Par::Seq).map_err(LocalError::Factor)?;
    f.solve_in_place(rhs.as_mut());
    if !rhs.col_iter().all(|c| c.iter().all(|x| x.is_finite())) {
        return Err(LocalError::NotFinite);
    }
    for (k, &v) in region.iter().enumerate() {
        d[v as usize] = [rhs[(k, 0)], rhs[(k, 1)]];
    }
    Ok(r)
}

/// `Δ_W` restricted to the region (upper triangle in compressed columns, assembled column by
/// column in the region's order) and the right-hand side `-g - Δ_W,RO d_O`, the neighbours
/// outside held at `d` (zero when pinned). Lists the region's triangles in `scratch.touched`.
fn region_system(
    p: &LocalProblem,
    region: &[u32],
    scratch: &mut LocalScratch,
    d: &[[f64; 2]],
) -> (SparseColMat<usize, f64>, Mat<f64>) {
    let (tris, cot) = (&p.frames.triangles, &p.frames.cot);
    let (vt_start, vt) = (&p.adjacency.0, &p.adjacency.1);
    let r = region.len();
    let mut rhs = Mat::<f64>::zeros(r, 2);
    let mut col_ptr = Vec::with_capacity(r + 1);
    let mut rows: Vec<usize> = Vec::with_capacity(5 * r);
    let mut vals: Vec<f64> = Vec::with_capacity(5 * r);
    let mut column: Vec<(usize, f64)> = Vec::new();
    col_ptr.push(0);
    for (k, &v) in region.iter().enumerate() {
        let f = p.row_of[v as usize] as usize;
        let (mut r0, mut r1) = (-p.gradient[(f, 0)], -p.gradient[(f, 1)]);
        let mut diag = 0.0;
        column.clear();
        for &t in &vt[vt_start[v as usize]..vt_start[v as usize + 1]] {
            if !scratch.seen[t as usize] {
                scratch.seen[t as usize] = true;
                scratch.touched.push(t);
            }
            let (t, tri) = (t as usize, tris[t as usize]);
            let c = (0..3).find(|&c| tri[c] == v).unwrap_or(0);
            // edge (v, tri[c+1]) is opposite corner c+2, edge (v, tri[c+2]) opposite c+1
            for (u, opposite) in [
                (tri[(c + 1) % 3], (c + 2) % 3),
                (tri[(c + 2) % 3], (c + 1) % 3),
            ] {
                let w = cot[t][opposite] * p.weights[t];
                diag += w;
                let ru = scratch.mark[u as usize];
                if ru == u32::MAX {
                    r0 += w * d[u as usize][0];
                    r1 += w * d[u as usize][1];
                } else if (ru as usize) < k {
                    match column.iter_mut().find(|e| e.0 == ru as usize) {
                        Some(e) => e.1 -= w,
                        None => column.push((ru as usize, -w)),
                    }
                }
            }
        }
        rhs[(k, 0)] = r0;
        rhs[(k, 1)] = r1;
        column.sort_unstable_by_key(|e| e.0);
        for &(row, val) in &column {
            rows.push(row);
            vals.push(val);
        }
        rows.push(k);
        vals.push(diag);
        col_ptr.push(rows.len());
    }
    let upper = SparseColMat::new(
        SymbolicSparseColMat::new_checked(r, r, col_ptr, None, rows),
        vals,
    );
    (upper, rhs)
}

/// Multiplies by `REWEIGHT_FACTOR` the weight of every triangle that would flip before
/// `best_step` (`limits < best_step`); returns how many changed. Between refactorizations a
/// triangle that keeps blocking keeps stiffening, so that it is frozen once the factor is
/// refreshed.
fn reweight(limits: &[f64], best_step: f64, weights: &mut [f64]) -> usize {
    let mut changed = 0;
    for (w, &lim) in weights.iter_mut().zip(limits) {
        if lim < best_step && *w < MAX_WEIGHT {
            *w = (*w * REWEIGHT_FACTOR).min(MAX_WEIGHT);
            changed += 1;
        }
    }
    changed
}

#[cfg(test)]
mod tests {
    use super::super::energy::evaluate;
    use super::super::local_global::tests::planar_grid;
    use super::super::system::{
        corner_weights, descent_direction, elimination_rows, fixed_vertices, free_rows,
        gradient_into, laplacian_triplets,
    };
    use super::*;

    /// `local_resolve` against the global step it refines: with unit weights the global step
    /// already minimizes the model on any region (so nothing changes), and with stiffened
    /// blocking triangles those stop deforming (`J(δ) → 0`: they only translate).
    #[test]
    fn local_resolve_keeps_the_global_step_and_freezes_stiff_triangles() {
        let (p, t) = planar_grid(12);
        let uv0: Vec<[f64; 2]> = p
            .iter()
            .map(|q| {
                [
                    1.3 * q[0] + 0.2 * q[1] * q[1],
                    0.8 * q[1] + 0.1 * q[0] * q[1],
                ]
            })
            .collect();
        let frames = TriangleFrames::new(&p, &t).unwrap();
        let (n, m) = (p.len(), frames.len());
        let fixed = fixed_vertices(n, &frames.triangles, None);
        let (free_index, free_vertices) = free_rows(&fixed);
        let (trip, _) = laplacian_triplets(&frames, &free_index);
        let factor = SpdFactor::new(free_vertices.len(), &trip, Par::Seq).unwrap();
        // rows in the factor's elimination order, as `iterate` keeps them
        let (row_of, row_vertex) = elimination_rows(&factor, &free_index);
        let mut targets = vec![[1.0, 0.0]; m];
        evaluate(&frames, &uv0, None, &mut targets);
        let mut g = Mat::<f64>::zeros(free_vertices.len(), 2);
        gradient_into(
            &frames,
            &corner_weights(&frames),
            &targets,
            &uv0,
            &row_of,
            &mut [Vec::new(), Vec::new()],
            &mut g,
        );
        let mut rhs = g.clone();
        let mut d = vec![[0.0; 2]; n];
        descent_direction(&factor, &g, &mut rhs, &row_vertex, &mut d);
        // the same direction as a solve in the free vertices' own order
        let mut g_free = Mat::<f64>::zeros(free_vertices.len(), 2);
        for (f, &v) in free_vertices.iter().enumerate() {
            for c in 0..2 {
                g_free[(f, c)] = -g[(row_of[v] as usize, c)];
            }
        }
        factor.solve_in_place(g_free.as_mut());
        for (f, &v) in free_vertices.iter().enumerate() {
            for c in 0..2 {
                assert!((g_free[(f, c)] - d[v][c]).abs() <= 1e-12 * (1.0 + d[v][c].abs()));
            }
        }
        // four triangles near the middle "block" the step
        let centre = |t: usize| {
            let c = frames.triangles[t].map(|v| p[v as usize]);
            [
                (c[0][0] + c[1][0] + c[2][0]) / 3.0,
                (c[0][1] + c[1][1] + c[2][1]) / 3.0,
            ]
        };
        let blocked: Vec<usize> = (0..m)
            .filter(|&t| {
                let c = centre(t);
                (c[0] - 0.5).abs() < 0.09 && (c[1] - 0.5).abs() < 0.05
            })
            .take(4)
            .collect();
        assert_eq!(blocked.len(), 4);
        let mut limits = vec![f64::INFINITY; m];
        for &b in &blocked {
            limits[b] = 0.1;
        }
        let adjacency = cgnodes_api::types::Topology::vertex_triangles(n, &frames.triangles);
        let mut scratch = LocalScratch::new(n, m);
        let dmax = d
            .iter()
            .map(|x| x[0].abs().max(x[1].abs()))
            .fold(0.0, f64::max);
        assert!(dmax > 1e-3);

        // a region larger than the cap is refused, the direction left as it was
        let stiff = vec![10.0; m];
        let base = LocalProblem {
            frames: &frames,
            weights: &stiff,
            limits: &limits,
            best_step: 1.0,
            rings: 2,
            max_region: 6,
            row_of: &row_of,
            gradient: &g,
            adjacency: &adjacency,
        };
        let mut d0 = d.clone();
        let refused = local_resolve(&base, &mut scratch, &mut d0);
        assert!(refused.is_err());
        assert_eq!(d0, d);
        let (mark, seen) = (&scratch.mark, &scratch.seen);
        assert!(mark.iter().all(|&x| x == u32::MAX) && seen.iter().all(|&x| !x));

        let mut resolve = |w: &[f64], d: &mut [[f64; 2]]| {
            let p = LocalProblem {
                weights: w,
                max_region: n,
                ..base
            };
            let r = local_resolve(&p, &mut scratch, d).unwrap();
            (r, scratch.touched.len())
        };
        let mut d1 = d.clone();
        let (r, changed) = resolve(&vec![1.0; m], &mut d1);
        assert!(r > 6 && r < n / 2, "region of {r} vertices");
        assert!(changed > 0);
        for (a, b) in d.iter().zip(&d1) {
            assert!((a[0] - b[0]).abs() + (a[1] - b[1]).abs() < 1e-9 * dmax);
        }

        let mut w = vec![1.0; m];
        for &b in &blocked {
            w[b] = 1e8;
        }
        let mut d2 = d.clone();
        resolve(&w, &mut d2);
        let (mark, seen) = (&scratch.mark, &scratch.seen);
        assert!(mark.iter().all(|&x| x == u32::MAX) && seen.iter().all(|&x| !x));
        let norm = |j: [[f64; 2]; 2]| {
            (j[0][0].powi(2) + j[0][1].powi(2) + j[1][0].powi(2) + j[1][1].powi(2)).sqrt()
        };
        for &b in &blocked {
            let (before, after) = (norm(frames.jacobian(b, &d)), norm(frames.jacobian(b, &d2)));
            assert!(before > 1e-3, "triangle {b} barely deforms: {before}");
            assert!(
                after < 1e-4 * before,
                "triangle {b}: |J(d)| {before} -> {after}"
            );
        }
        // outside the region the global step is kept
        let region: Vec<bool> = (0..n).map(|v| d2[v] != d[v]).collect();
        assert!(region.iter().filter(|&&x| x).count() <= r);
    }
}
