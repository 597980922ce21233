//! The global step of the local/global iteration (Liu et al. 2008, eq. 6), as a
//! preconditioned gradient step: which vertices are free, the cotangent Laplacian on them
//! (tagged by triangle for the fold-free reweighting), the right-hand side's corner weights,
//! the gradient, and the solve in the factor's elimination order.

use super::component_of;
use super::frames::{Similarity, TriangleFrames, PAR_CHUNK};
use cgnodes_linalg::SpdFactor;
use faer::sparse::Triplet;
use faer::Mat;
use rayon::prelude::*;

/// Marks one vertex per connected component (the `pin` in its component, otherwise the
/// component's lowest vertex) and every vertex that no triangle uses.
pub(super) fn fixed_vertices(n: usize, triangles: &[[u32; 3]], pin: Option<usize>) -> Vec<bool> {
    let (comp, ncomp) = component_of(n, triangles);
    let mut fixed: Vec<bool> = comp.iter().map(|&c| c == u32::MAX).collect();
    let mut has_pin = vec![false; ncomp];
    if let Some(p) = pin.filter(|&p| comp[p] != u32::MAX) {
        has_pin[comp[p] as usize] = true;
        fixed[p] = true;
    }
    for v in 0..n {
        let c = comp[v];
        if c != u32::MAX && !has_pin[c as usize] {
            has_pin[c as usize] = true;
            fixed[v] = true;
        }
    }
    fixed
}

/// Numbers the vertices that are not `fixed`, in vertex order: each vertex's row
/// (`u32::MAX` when fixed) and the vertex of each row.
pub(super) fn free_rows(fixed: &[bool]) -> (Vec<u32>, Vec<usize>) {
    let mut free_index = vec![u32::MAX; fixed.len()];
    let mut free_vertices = Vec::new();
    for (v, &f) in fixed.iter().enumerate() {
        if !f {
            free_index[v] = free_vertices.len() as u32;
            free_vertices.push(v);
        }
    }
    (free_index, free_vertices)
}

/// The cotangent Laplacian on the free vertices (lower-triangle triplets; `free_index` maps a
/// vertex to its row, `u32::MAX` when pinned), each entry tagged with its triangle so that the
/// fold-free mode can reweight triangles (see `reweight`).
pub(super) fn laplacian_triplets(
    frames: &TriangleFrames,
    free_index: &[u32],
) -> (Vec<Triplet<usize, usize, f64>>, Vec<u32>) {
    let m = frames.len();
    let mut trip: Vec<Triplet<usize, usize, f64>> = Vec::with_capacity(9 * m);
    let mut trip_tri: Vec<u32> = Vec::with_capacity(9 * m);
    for t in 0..m {
        let tri = frames.triangles[t];
        for k in 0..3 {
            let (i, j) = (tri[(k + 1) % 3] as usize, tri[(k + 2) % 3] as usize);
            let w = frames.cot[t][k];
            let (fi, fj) = (free_index[i], free_index[j]);
            let mut push = |r: u32, c: u32, v: f64| {
                trip.push(Triplet::new(r as usize, c as usize, v));
                trip_tri.push(t as u32);
            };
            if fi != u32::MAX {
                push(fi, fi, w);
            }
            if fj != u32::MAX {
                push(fj, fj, w);
            }
            if fi != u32::MAX && fj != u32::MAX {
                push(fi.max(fj), fi.min(fj), -w);
            }
        }
    }
    (trip, trip_tri)
}

/// Right-hand side weights per corner: `b_i += L_t · w_t,i` with
/// `w_t,i = Σ_(j≠i) cot θ_ij (x_i - x_j)` (Liu et al. 2008, eq. 6).
pub(super) fn corner_weights(frames: &TriangleFrames) -> Vec<[[f64; 2]; 3]> {
    (0..frames.len())
        .into_par_iter()
        .with_min_len(PAR_CHUNK)
        .map(|t| {
            let x = frames.local[t];
            let c = frames.cot[t];
            let mut w = [[0.0; 2]; 3];
            for k in 0..3 {
                let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
                // edge (k, k1) is opposite corner k2, edge (k, k2) opposite corner k1
                for d in 0..2 {
                    w[k][d] = c[k2] * (x[k][d] - x[k1][d]) + c[k1] * (x[k][d] - x[k2][d]);
                }
            }
            w
        })
        .collect()
}

/// `∇E` on the free vertices (row `row_of[v]`, `u32::MAX` for a fixed vertex), written to
/// `out`: at vertex i, `Σ_t Σ_j cot θ_ij ((u_i - u_j) - L_t (x_i - x_j))` (Liu et al. 2008,
/// eq. 6). The two halves of the triangle list are scattered into the two `halves` buffers
/// (one per vertex, resized here) on two threads, then summed; the split does not depend on
/// the thread count, so neither does the result. A parallel gather per vertex over its
/// triangles measured slower, its reads of the UVs being scattered (timings: docs/arap.md).
pub(super) fn gradient_into(
    frames: &TriangleFrames,
    corner_w: &[[[f64; 2]; 3]],
    targets: &[Similarity],
    uv: &[[f64; 2]],
    row_of: &[u32],
    halves: &mut [Vec<[f64; 2]>; 2],
    out: &mut Mat<f64>,
) {
    let m = frames.len();
    let scatter = |range: std::ops::Range<usize>, acc: &mut Vec<[f64; 2]>| {
        acc.clear();
        acc.resize(uv.len(), [0.0; 2]);
        for t in range {
            let [a, b] = targets[t];
            let tri = frames.triangles[t];
            let c = frames.cot[t];
            for k in 0..3 {
                let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
                let (u, u1, u2) = (
                    uv[tri[k] as usize],
                    uv[tri[k1] as usize],
                    uv[tri[k2] as usize],
                );
                let w = corner_w[t][k];
                let lw = [a * w[0] - b * w[1], b * w[0] + a * w[1]];
                let g = &mut acc[tri[k] as usize];
                for dim in 0..2 {
                    g[dim] += c[k2] * (u[dim] - u1[dim]) + c[k1] * (u[dim] - u2[dim]) - lw[dim];
                }
            }
        }
    };
    let [h0, h1] = halves;
    rayon::join(|| scatter(0..m / 2, h0), || scatter(m / 2..m, h1));
    for (v, &fi) in row_of.iter().enumerate() {
        if fi != u32::MAX {
            for dim in 0..2 {
                out[(fi as usize, dim)] = h0[v][dim] + h1[v][dim];
            }
        }
    }
}

/// The gradient, the solves and the local re-solves keep the free vertices in the factor's
/// elimination order, so that a solve needs no permuted copies
/// (`SpdFactor::solve_in_elimination_order`). Returns each vertex's row in that order
/// (`u32::MAX` when fixed, i.e. `free_index[v] == u32::MAX`) and the vertex of each row.
pub(super) fn elimination_rows(factor: &SpdFactor, free_index: &[u32]) -> (Vec<u32>, Vec<usize>) {
    let position = factor.elimination_position();
    let row_of: Vec<u32> = free_index
        .iter()
        .map(|&f| {
            if f == u32::MAX {
                f
            } else {
                position[f as usize] as u32
            }
        })
        .collect();
    let mut row_vertex = vec![0usize; position.len()];
    for (v, &r) in row_of.iter().enumerate() {
        if r != u32::MAX {
            row_vertex[r as usize] = v;
        }
    }
    (row_of, row_vertex)
}

/// `d = -Δ_W⁻¹ g` for the gradient `g` (one row per free vertex, in the factor's elimination
/// order; `rhs` is the solve's scratch), scattered to the free vertices (`row_vertex[k]`: the
/// vertex of row `k`); pinned vertices keep their zero direction.
pub(super) fn descent_direction(
    factor: &SpdFactor,
    gradient: &Mat<f64>,
    rhs: &mut Mat<f64>,
    row_vertex: &[usize],
    d: &mut [[f64; 2]],
) {
    rhs.copy_from(gradient);
    factor.solve_in_elimination_order(rhs.as_mut());
    for (k, &v) in row_vertex.iter().enumerate() {
        d[v] = [-rhs[(k, 0)], -rhs[(k, 1)]];
    }
}
