//! The compressed-column copy of a supernodal factor (for repeated solves with few
//! right-hand sides) and the extraction of a trailing block of the factor.

use super::SpdFactor;
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::Mat;

impl SpdFactor {
    /// Prepares for many solves with this factor (and its refactorizations): a supernodal
    /// factor is copied into compressed columns, now and after every refactorization. The
    /// first copy walks and allocates the whole factor (on nefertiti_front's Tutte system it
    /// cost more than the one solve it would speed up); later ones only gather the values.
    pub fn prepare_many_solves(&mut self) {
        self.many_solves = true;
        self.update_columns();
    }

    /// Refreshes `columns` after a numeric factorization (see `columns`).
    pub(super) fn update_columns(&mut self) {
        let SymbolicCholeskyRaw::Supernodal(sym) = self.symbolic.raw() else {
            return;
        };
        let values = &self.values;
        if let Some(l) = self.columns.as_mut() {
            if self.dropped.iter().all(|&k| values[k] == 0.0) {
                for (v, &k) in l.val_mut().iter_mut().zip(&self.gather) {
                    *v = values[k];
                }
                return;
            }
        }
        let n = sym.nrows();
        if u32::try_from(values.len()).is_err() {
            // too large for 4-byte indices: faer's supernodal solve instead
            self.columns = None;
            return;
        }
        let mut col_ptr: Vec<u32> = Vec::with_capacity(n + 1);
        let mut rows: Vec<u32> = Vec::with_capacity(values.len());
        let (mut gather, mut dropped) = (Vec::with_capacity(values.len()), Vec::new());
        for_each_supernodal_entry(sym, 0, |col, row, k| {
            if row == col {
                // the diagonal comes first, as faer's sparse triangular solves expect
                col_ptr.push(rows.len() as u32);
            }
            if row == col || values[k] != 0.0 {
                rows.push(row as u32);
                gather.push(k);
            } else {
                dropped.push(k);
            }
        });
        col_ptr.push(rows.len() as u32);
        let vals = gather.iter().map(|&k| values[k]).collect();
        // faer checks the pattern (pointers increasing, rows in range)
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, rows);
        self.columns = Some(SparseColMat::new(symbolic, vals));
        (self.gather, self.dropped) = (gather, dropped);
    }

    /// The trailing `s x s` block of the factor `L` (its last `s` columns, rows at or below
    /// the diagonal), when the factor was computed in stored order (no permutation): `L_ss`
    /// with `L_ss L_ssᵀ` the Schur complement of the last `s` unknowns. `None` when the
    /// factor is permuted or `s` exceeds its size.
    pub fn trailing_block(&self, s: usize) -> Option<Mat<f64>> {
        let n = self.dim();
        if s > n || self.symbolic.perm().is_some() {
            return None;
        }
        let first = n - s;
        let mut x = Mat::<f64>::zeros(s, s);
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(sym) => {
                for_each_supernodal_entry(sym, first, |col, row, k| {
                    x[(row - first, col - first)] = self.values[k];
                });
            }
            SymbolicCholeskyRaw::Simplicial(sym) => {
                let (col_ptr, rows) = (sym.col_ptr(), sym.row_idx());
                for j in first..n {
                    for k in col_ptr[j]..col_ptr[j + 1] {
                        x[(rows[k] - first, j - first)] = self.values[k];
                    }
                }
            }
        }
        Some(x)
    }
}

/// Calls `visit(column, row, index in the values)` for every stored entry of a supernodal
/// factor's columns `first..`, column by column, the diagonal first in each column. Each
/// supernode is a column-major `nrows x ncols` block whose top `ncols` rows are its diagonal
/// block and the rest its `below` pattern.
fn for_each_supernodal_entry(
    sym: &SymbolicSupernodalCholesky<usize>,
    first: usize,
    mut visit: impl FnMut(usize, usize, usize),
) {
    let (begin, end) = (sym.supernode_begin(), sym.supernode_end());
    let (row_ptr, val_ptr, pattern) = (
        sym.col_ptr_for_row_idx(),
        sym.col_ptr_for_val(),
        sym.row_idx(),
    );
    for s in 0..sym.n_supernodes() {
        if end[s] <= first {
            continue;
        }
        let (start, ncols) = (begin[s], end[s] - begin[s]);
        let below = &pattern[row_ptr[s]..row_ptr[s + 1]];
        let nrows = ncols + below.len();
        for j in first.max(start) - start..ncols {
            let col = val_ptr[s] + j * nrows;
            for i in j..nrows {
                let row = if i < ncols {
                    start + i
                } else {
                    below[i - ncols]
                };
                visit(start + j, row, col + i);
            }
        }
    }
}
