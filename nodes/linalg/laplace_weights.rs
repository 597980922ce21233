//! The Dirichlet (fixed-value) solve of a Laplace system given as a list of directed edge
//! weights, which need not be symmetric (Floater's mean-value weights are not): row `i` is
//! `sum_j w_ij (x_i - x_j) = 0`. The free-vertex block is assembled in compressed columns and
//! factored with a sparse LU, or with a sparse Cholesky when the weights are symmetric. For
//! symmetric weights in compressed rows, `laplace.rs` is the faster path (nested dissection,
//! two cores).

use super::laplace::not_positive_definite;
use super::SpdFactor;
use cgnodes_api::node::NodeError;
use faer::linalg::solvers::Solve;
use faer::sparse::SparseColMat;
use faer::Mat;

/// A directed edge weight: row vertex, column vertex, weight.
pub type EdgeWeight = (u32, u32, f64);

/// The interior (free-vertex) block of a Laplace system with Dirichlet conditions, ready to
/// factor: `matrix` (only the lower triangle when assembled as symmetric), the right-hand side
/// with one column per coordinate, and the row of each vertex (`u32::MAX` for fixed ones).
pub struct DirichletSystem<const D: usize> {
    /// Free-vertex system matrix, `L_II`.
    pub matrix: SparseColMat<usize, f64>,
    /// `-L_IB x_B`, one column per coordinate.
    pub rhs: Mat<f64>,
    /// Row of each vertex in the system, `u32::MAX` for fixed vertices.
    pub index: Vec<u32>,
}

/// Assembles the free-vertex system of `sum_j w_ij (x_i - x_j) = 0` with the vertices where
/// `fixed[i]` is `Some` moved to the right-hand side. With `symmetric`, only the lower triangle
/// is stored (for a Cholesky factorization). Duplicate weights are summed. Entries are bucketed
/// by column with a counting sort (linear time), then each short column is sorted.
pub fn assemble_dirichlet<const D: usize>(
    weights: &[EdgeWeight],
    fixed: &[Option<[f64; D]>],
    symmetric: bool,
) -> Result<DirichletSystem<D>, NodeError> {
    let n = fixed.len();
    let mut index = vec![u32::MAX; n];
    let mut nfree = 0usize;
    for (v, f) in fixed.iter().enumerate() {
        if f.is_none() {
            index[v] = nfree as u32;
            nfree += 1;
        }
    }
    let mut diag = vec![0.0; nfree];
    let mut rhs = Mat::<f64>::zeros(nfree, D);
    // count off-diagonal entries per column
    let mut col_start = vec![0usize; nfree + 2];
    for &(i, j, _) in weights {
        let (ri, cj) = (index[i as usize], index[j as usize]);
        if ri != u32::MAX && cj != u32::MAX && (!symmetric || ri > cj) {
            col_start[cj as usize + 2] += 1;
        }
    }
    // one diagonal entry per column
    for c in 0..nfree {
        col_start[c + 2] += 1;
    }
    for c in 1..nfree + 2 {
        col_start[c] += col_start[c - 1];
    }
    let nnz = col_start[nfree + 1];
    let mut rows = vec![0u32; nnz];
    let mut vals = vec![0.0f64; nnz];
    // fill: col_start[c + 1] is the next free slot of column c
    for &(i, j, w) in weights {
        let ri = index[i as usize];
        if ri == u32::MAX {
            continue;
        }
        diag[ri as usize] += w;
        let cj = index[j as usize];
        if cj == u32::MAX {
            let x = fixed[j as usize].unwrap_or([0.0; D]);
            for (d, xd) in x.iter().enumerate() {
                rhs[(ri as usize, d)] += w * xd;
            }
        } else if !symmetric || ri > cj {
            let s = &mut col_start[cj as usize + 1];
            rows[*s] = ri;
            vals[*s] = -w;
            *s += 1;
        }
    }
    for (c, &d) in diag.iter().enumerate() {
        if d.abs() <= 1e-300 || !d.is_finite() {
            let v = index.iter().position(|&r| r == c as u32).unwrap_or(0);
            return Err(NodeError::singular(format!(
                "free vertex {v} has no usable edge weights (isolated or degenerate neighbourhood)"
            )));
        }
        let s = &mut col_start[c + 1];
        rows[*s] = c as u32;
        vals[*s] = d;
        *s += 1;
    }
    // col_start[c] .. col_start[c + 1] is now column c; sort rows and merge duplicates
    let mut col_ptr = Vec::with_capacity(nfree + 1);
    let mut row_idx = Vec::with_capacity(nnz);
    let mut values = Vec::with_capacity(nnz);
    let mut pairs: Vec<(u32, f64)> = Vec::new();
    col_ptr.push(0usize);
    for c in 0..nfree {
        pairs.clear();
        pairs.extend((col_start[c]..col_start[c + 1]).map(|k| (rows[k], vals[k])));
        pairs.sort_unstable_by_key(|p| p.0);
        for &(r, v) in &pairs {
            if row_idx.len() > col_ptr[c] && row_idx.last() == Some(&(r as usize)) {
                *values.last_mut().unwrap() += v;
            } else {
                row_idx.push(r as usize);
                values.push(v);
            }
        }
        col_ptr.push(row_idx.len());
    }
    let symbolic =
        faer::sparse::SymbolicSparseColMat::new_checked(nfree, nfree, col_ptr, None, row_idx);
    let matrix = SparseColMat::new(symbolic, values);
    Ok(DirichletSystem { matrix, rhs, index })
}

/// Solves the Laplace equation `sum_j w_ij (x_i - x_j) = 0` for every free vertex `i`, with
/// the vertices where `fixed[i]` is `Some` held at those values (Dirichlet conditions moved
/// to the right-hand side). `symmetric` selects a sparse Cholesky factorization (the weights
/// must then be symmetric, `w_ij = w_ji`); otherwise a sparse LU. All `D` coordinates share
/// one factorization. A free vertex without weights, or a singular system, is an error.
pub fn solve_dirichlet_weights<const D: usize>(
    weights: &[EdgeWeight],
    fixed: &[Option<[f64; D]>],
    symmetric: bool,
) -> Result<Vec<[f64; D]>, NodeError> {
    let mut out: Vec<[f64; D]> = fixed.iter().map(|f| f.unwrap_or([0.0; D])).collect();
    if fixed.iter().all(|f| f.is_some()) {
        return Ok(out);
    }
    let DirichletSystem { matrix, rhs, index } = assemble_dirichlet(weights, fixed, symmetric)?;
    let x = if symmetric {
        // faer's AMD order; one thread (see `SpdFactor`)
        let factor =
            SpdFactor::from_lower(matrix, None, faer::Par::Seq).map_err(not_positive_definite)?;
        let mut x = rhs;
        factor.solve_in_place(x.as_mut());
        x
    } else {
        matrix
            .sp_lu()
            .map_err(|e| NodeError::singular(format!("the Laplace system is singular ({e:?})")))?
            .solve(&rhs)
    };
    for (v, &r) in index.iter().enumerate() {
        if r != u32::MAX {
            for d in 0..D {
                let val = x[(r as usize, d)];
                if !val.is_finite() {
                    return Err(NodeError::singular(
                        "the Laplace solve produced non-finite values (singular system)",
                    ));
                }
                out[v][d] = val;
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dirichlet_on_a_path_is_linear() {
        // path 0-1-2-3 with ends fixed at 0 and 3: interior values 1 and 2
        let w: Vec<EdgeWeight> = (0..3u32)
            .flat_map(|i| [(i, i + 1, 1.0), (i + 1, i, 1.0)])
            .collect();
        let fixed = vec![Some([0.0]), None, None, Some([3.0])];
        for sym in [true, false] {
            let x = solve_dirichlet_weights(&w, &fixed, sym).unwrap();
            assert!((x[1][0] - 1.0).abs() < 1e-12 && (x[2][0] - 2.0).abs() < 1e-12);
        }
        // a free vertex without weights is refused, not a panic
        let fixed = vec![Some([0.0]), None, None, Some([3.0]), None];
        assert!(solve_dirichlet_weights(&w, &fixed, true).is_err());
    }
}
