//! The discrete Poisson matrix over Ω (Pérez et al. 2003, eq. 7): for each inside pixel p,
//! `|N_p| f_p - Σ_{q ∈ N_p ∩ Ω} f_q = (Dirichlet values and guidance, see guidance.rs)`.
//! Ω never touches the target's border, so |N_p| = 4 everywhere: 4 on the diagonal, -1 for
//! each inside 4-neighbour. The matrix is symmetric, diagonally dominant, and strictly so at
//! each pixel next to ∂Ω, hence positive definite (every component of Ω touches ∂Ω).

use super::mask::MaskShape;
use crate::nodes::linalg::SpdFactor;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Mat, MatRef};
use rayon::prelude::*;

/// The lower triangle of the Poisson matrix in compressed columns. Unknowns are numbered
/// row-major, so column k holds the diagonal, then the right neighbour, then the one below
/// (rows already sorted).
pub fn poisson_matrix(shape: &MaskShape) -> SparseColMat<usize, f64> {
    let n = shape.len();
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::with_capacity(3 * n);
    let mut values = Vec::with_capacity(3 * n);
    col_ptr.push(0usize);
    for (k, &[x, y]) in shape.inside.iter().enumerate() {
        row_idx.push(k);
        values.push(4.0);
        for (dx, dy) in [(1, 0), (0, 1)] {
            if let Some(q) = shape.unknown(x as i64 + dx, y as i64 + dy) {
                row_idx.push(q);
                values.push(-1.0);
            }
        }
        col_ptr.push(row_idx.len());
    }
    let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
    SparseColMat::new(symbolic, values)
}

/// Factors the Poisson matrix of `shape` (sparse Cholesky, faer's AMD ordering).
pub fn factor(shape: &MaskShape) -> Result<SpdFactor, String> {
    SpdFactor::from_lower(poisson_matrix(shape), None, faer::Par::Seq)
}

/// `A x` for the Poisson matrix of `shape`, every column of `x` (for residuals).
pub fn apply(shape: &MaskShape, x: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::zeros(x.nrows(), x.ncols());
    for_each_row(shape, x, |k, c, v| out[(k, c)] = v);
    out
}

/// `||b - A x||` (Frobenius over the columns), without forming `A x`; in parallel chunks.
pub fn residual_norm(shape: &MaskShape, x: MatRef<'_, f64>, b: MatRef<'_, f64>) -> f64 {
    if let Some([w, h]) = shape.rectangle() {
        return rect_residual_norm(w as usize, h as usize, x, b);
    }
    let n = shape.len();
    let sum: f64 = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|t| {
            let mut sum = 0.0;
            for k in t * CHUNK..((t + 1) * CHUNK).min(n) {
                let [px, py] = shape.inside[k];
                let (px, py) = (px as i64, py as i64);
                let nb = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                    .map(|(dx, dy)| shape.unknown(px + dx, py + dy));
                for c in 0..x.ncols() {
                    let mut v = 4.0 * x[(k, c)];
                    for q in nb.iter().flatten() {
                        v -= x[(*q, c)];
                    }
                    let r = b[(k, c)] - v;
                    sum += r * r;
                }
            }
            sum
        })
        .sum();
    sum.sqrt()
}

/// Unknowns (or rectangle rows) per parallel task of the residual.
const CHUNK: usize = 1 << 14;

/// `residual_norm` for a whole `w x h` rectangle: the stencil on row-major columns, without
/// looking up the numbering; rows in parallel.
fn rect_residual_norm(w: usize, h: usize, x: MatRef<'_, f64>, b: MatRef<'_, f64>) -> f64 {
    let sum: f64 = (0..x.ncols() * h)
        .into_par_iter()
        .with_min_len(16)
        .map(|cy| {
            let (c, y) = (cy / h, cy % h);
            let (xc, bc) = (x.col(c), b.col(c));
            let mut sum = 0.0;
            for i in y * w..(y + 1) * w {
                let mut v = 4.0 * xc[i];
                if i % w > 0 {
                    v -= xc[i - 1];
                }
                if i % w + 1 < w {
                    v -= xc[i + 1];
                }
                if y > 0 {
                    v -= xc[i - w];
                }
                if y + 1 < h {
                    v -= xc[i + w];
                }
                let r = bc[i] - v;
                sum += r * r;
            }
            sum
        })
        .sum();
    sum.sqrt()
}

/// Calls `f(k, c, (A x)[k, c])` for every unknown and column.
fn for_each_row(shape: &MaskShape, x: MatRef<'_, f64>, mut f: impl FnMut(usize, usize, f64)) {
    for (k, &[px, py]) in shape.inside.iter().enumerate() {
        let (px, py) = (px as i64, py as i64);
        let nb = [(1, 0), (-1, 0), (0, 1), (0, -1)].map(|(dx, dy)| shape.unknown(px + dx, py + dy));
        for c in 0..x.ncols() {
            let mut v = 4.0 * x[(k, c)];
            for q in nb.iter().flatten() {
                v -= x[(*q, c)];
            }
            f(k, c, v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matrix_entries_and_solve() {
        // an L of three pixels: (1,1) (2,1) (1,2)
        let mut flags = vec![false; 16];
        for i in [5, 6, 9] {
            flags[i] = true;
        }
        let shape = MaskShape::from_flags(4, 4, &flags);
        let a = poisson_matrix(&shape);
        let dense = a.to_dense();
        // lower triangle: 4 on the diagonal, -1 below for (2,1)-(1,1) and (1,2)-(1,1)
        assert_eq!(dense[(0, 0)], 4.0);
        assert_eq!(dense[(1, 0)], -1.0);
        assert_eq!(dense[(2, 0)], -1.0);
        assert_eq!(dense[(2, 1)], 0.0);
        let f = factor(&shape).unwrap();
        let b = Mat::from_fn(3, 2, |i, j| (i + 2 * j) as f64 + 1.0);
        let mut x = b.clone();
        f.solve_in_place(x.as_mut());
        let r = apply(&shape, x.as_ref()) - &b;
        assert!(r.norm_l2() < 1e-12 * b.norm_l2());
    }
}
