//! A sparse symmetric positive definite system factored once (faer's sparse Cholesky) and
//! solved for several right-hand sides per call.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, MatMut, Par, Side};

/// `L Lᵀ` of a sparse SPD matrix (fill-reducing ordering chosen by faer).
///
/// The factorization runs with the given parallelism; the triangular solves run on one
/// thread: for the two right-hand sides of a parameterization they are memory-bound, and on
/// the 2-core benchmark machine faer's parallel solve was several times slower.
pub struct SpdFactor {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    /// The matrix (lower triangle, compressed columns), kept for numeric refactorization.
    matrix: SparseColMat<usize, f64>,
    /// For each triplet given to `new`, the index of its entry in `matrix`'s values, so that
    /// `refactor_with` assembles new values without sorting.
    slot: Vec<usize>,
}

impl SpdFactor {
    /// Factors the `n x n` matrix given by its lower-triangle triplets (duplicates are summed).
    /// A matrix that is not positive definite gives `Err` with faer's reason.
    pub fn new(
        n: usize,
        lower: &[Triplet<usize, usize, f64>],
        par: Par,
    ) -> Result<SpdFactor, String> {
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, lower)
            .map_err(|e| format!("assembling the sparse matrix: {e:?}"))?;
        let symbolic = factorize_symbolic_cholesky(
            a.symbolic(),
            Side::Lower,
            Default::default(),
            Default::default(),
        )
        .map_err(|e| format!("symbolic Cholesky: {e:?}"))?;
        let values = vec![0.0; symbolic.len_val()];
        // where each triplet lands (row indices are sorted within a column)
        let slot = {
            let (col_ptr, row_idx) = (a.symbolic().col_ptr(), a.symbolic().row_idx());
            lower
                .iter()
                .map(|t| {
                    let rows = &row_idx[col_ptr[t.col]..col_ptr[t.col + 1]];
                    col_ptr[t.col] + rows.binary_search(&t.row).expect("entry in pattern")
                })
                .collect()
        };
        let mut f = SpdFactor {
            symbolic,
            values,
            matrix: a,
            slot,
        };
        f.numeric(par)?;
        Ok(f)
    }

    /// Factors the matrix given by its lower triangle in compressed columns, with the given
    /// elimination order (the `k`-th entry is the row eliminated `k`-th; faer's AMD when `None`
    /// or when it is not a permutation). `refactor_with` then takes one value per stored entry,
    /// in storage order.
    pub fn from_lower(
        a: SparseColMat<usize, f64>,
        order: Option<&[usize]>,
        par: Par,
    ) -> Result<SpdFactor, String> {
        use faer::sparse::linalg::cholesky::SymmetricOrdering;
        let n = a.nrows();
        let perm = order.filter(|o| o.len() == n).and_then(|fwd| {
            let mut inv = vec![usize::MAX; n];
            for (k, &v) in fwd.iter().enumerate() {
                let slot = inv.get_mut(v)?;
                if *slot != usize::MAX {
                    return None;
                }
                *slot = k;
            }
            Some((fwd, inv))
        });
        let ordering = match &perm {
            Some((fwd, inv)) => {
                SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(fwd, inv, n))
            }
            None => SymmetricOrdering::Amd,
        };
        let symbolic =
            factorize_symbolic_cholesky(a.symbolic(), Side::Lower, ordering, Default::default())
                .map_err(|e| format!("symbolic Cholesky: {e:?}"))?;
        let mut f = SpdFactor {
            values: vec![0.0; symbolic.len_val()],
            symbolic,
            slot: (0..a.val().len()).collect(),
            matrix: a,
        };
        f.numeric(par)?;
        Ok(f)
    }

    /// Factors new values with the same pattern as the matrix given to `new` (the symbolic
    /// analysis, ordering included, is reused).
    pub fn refactor(
        &mut self,
        lower: &[Triplet<usize, usize, f64>],
        par: Par,
    ) -> Result<(), String> {
        self.refactor_with(lower.len(), |k| lower[k].val, par)
    }

    /// Like `refactor`, with the value of the `k`-th triplet given to `new` read from
    /// `value(k)` (`count` must be the number of those triplets): no sorting, no allocation
    /// beyond the factorization's workspace.
    pub fn refactor_with(
        &mut self,
        count: usize,
        value: impl Fn(usize) -> f64,
        par: Par,
    ) -> Result<(), String> {
        if count != self.slot.len() {
            return Err(format!(
                "refactor with {count} entries, the pattern has {}",
                self.slot.len()
            ));
        }
        let vals = self.matrix.val_mut();
        vals.fill(0.0);
        for (k, &s) in self.slot.iter().enumerate() {
            vals[s] += value(k);
        }
        self.numeric(par)
    }

    fn numeric(&mut self, par: Par) -> Result<(), String> {
        let a = &self.matrix;
        let mut mem = MemBuffer::try_new(
            self.symbolic
                .factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        )
        .map_err(|e| format!("Cholesky workspace: {e:?}"))?;
        self.symbolic
            .factorize_numeric_llt(
                &mut self.values,
                a.as_ref(),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| format!("Cholesky: {e:?}"))?;
        Ok(())
    }

    /// Number of unknowns.
    pub fn dim(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Number of stored entries of the factor (a measure of the cost of one solve).
    pub fn factor_nnz(&self) -> usize {
        self.values.len()
    }

    /// Solves `A X = B` in place, every column of `rhs` at once.
    pub fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        let mut mem = MemBuffer::new(
            self.symbolic
                .solve_in_place_scratch::<f64>(rhs.ncols(), Par::Seq),
        );
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut mem),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_path_laplacian_and_refuses_a_singular_one() {
        let n = 6;
        let mut t = Vec::new();
        for i in 0..n {
            t.push(Triplet::new(i, i, 2.0));
            if i + 1 < n {
                t.push(Triplet::new(i + 1, i, -1.0));
            }
        }
        let f = SpdFactor::new(n, &t, Par::Seq).unwrap();
        // x = i+1 for i < n gives b = 0 except b[n-1] = n+1
        let mut b = faer::Mat::<f64>::zeros(n, 2);
        b[(n - 1, 0)] = (n + 1) as f64;
        b[(n - 1, 1)] = 2.0 * (n + 1) as f64;
        f.solve_in_place(b.as_mut());
        for i in 0..n {
            assert!((b[(i, 0)] - (i + 1) as f64).abs() < 1e-12);
            assert!((b[(i, 1)] - 2.0 * (i + 1) as f64).abs() < 1e-12);
        }
        // pure Neumann: singular
        t[0] = Triplet::new(0, 0, 1.0);
        t[2 * (n - 1)] = Triplet::new(n - 1, n - 1, 1.0);
        assert!(SpdFactor::new(n, &t, Par::Seq).is_err());
        // refactor with doubled values: the solution halves
        t[0] = Triplet::new(0, 0, 2.0);
        t[2 * (n - 1)] = Triplet::new(n - 1, n - 1, 2.0);
        let mut f = SpdFactor::new(n, &t, Par::Seq).unwrap();
        let t2: Vec<_> = t
            .iter()
            .map(|x| Triplet::new(x.row, x.col, 2.0 * x.val))
            .collect();
        f.refactor(&t2, Par::Seq).unwrap();
        let mut b = faer::Mat::<f64>::zeros(n, 1);
        b[(n - 1, 0)] = (n + 1) as f64;
        f.solve_in_place(b.as_mut());
        assert!((b[(0, 0)] - 0.5).abs() < 1e-12);
    }
}
