//! A sparse symmetric positive definite system factored once (faer's sparse Cholesky) and
//! solved for several right-hand sides per call.
//!
//! This file holds the factor and its symbolic (ordering) and numeric factorizations;
//! `columns.rs` the compressed-column copy of a supernodal factor, `solve.rs` the solves.

mod columns;
mod solve;
#[cfg(test)]
mod tests;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Par, Side};

/// `L Lᵀ` of a sparse SPD matrix (fill-reducing ordering chosen by faer).
///
/// The factorization runs with the given parallelism; the triangular solves run on one
/// thread: for the two right-hand sides of a parameterization they are memory-bound, and on
/// the 2-core benchmark machine faer's parallel solve was several times slower.
///
/// For repeated solves (`prepare_many_solves`) a supernodal factor is also copied into
/// compressed columns and solved with faer's sparse triangular solves: for one or two
/// right-hand sides the supernodal solve spends most of its time setting up small dense
/// products.
pub struct SpdFactor {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    /// The supernodal factor in compressed columns (permuted order, diagonal first in each
    /// column, exact zeros of relaxed supernodes dropped); `None` for a simplicial factor.
    /// Indexed by `u32`: the solves stream the whole factor for two right-hand sides, and
    /// 4-byte row indices make each entry 12 bytes instead of 16.
    columns: Option<SparseColMat<u32, f64>>,
    /// For each entry of `columns`, its index in `values`; and the indices of `values` left
    /// out as zeros. A refactorization whose left-out entries are still zero (the padding of
    /// relaxed supernodes always is) only gathers the values again.
    gather: Vec<usize>,
    dropped: Vec<usize>,
    /// Whether `columns` is kept (see `prepare_many_solves`).
    many_solves: bool,
    /// A simplicial factor's copy for `solve3`, made at its first call after each
    /// factorization.
    interleaved: std::sync::OnceLock<solve::Compact>,
    /// The matrix (one triangle, compressed columns), kept for numeric refactorization.
    matrix: SparseColMat<usize, f64>,
    /// Which triangle `matrix` holds.
    side: Side,
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
        Self::with_kind(n, lower, par, SupernodalThreshold::AUTO)
    }

    /// `new` with faer's supernodal factorization whatever its flop-ratio heuristic says: for
    /// a matrix refactored many times, where the heuristic, tuned for one factorization,
    /// picks the simplicial one too early. On the 10k-vertex ARAP Laplacian of
    /// `bunny_base4` (2-D mesh, AMD order) the supernodal numeric refactorization is about
    /// a quarter faster than the simplicial one faer picks; on 2.5k vertices it is slower.
    pub fn new_supernodal(
        n: usize,
        lower: &[Triplet<usize, usize, f64>],
        par: Par,
    ) -> Result<SpdFactor, String> {
        Self::with_kind(n, lower, par, SupernodalThreshold::FORCE_SUPERNODAL)
    }

    fn with_kind(
        n: usize,
        lower: &[Triplet<usize, usize, f64>],
        par: Par,
        threshold: SupernodalThreshold,
    ) -> Result<SpdFactor, String> {
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, lower)
            .map_err(|e| format!("assembling the sparse matrix: {e:?}"))?;
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: threshold,
            ..Default::default()
        };
        let symbolic =
            factorize_symbolic_cholesky(a.symbolic(), Side::Lower, Default::default(), params)
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
            columns: None,
            gather: Vec::new(),
            dropped: Vec::new(),
            many_solves: false,
            interleaved: std::sync::OnceLock::new(),
            matrix: a,
            side: Side::Lower,
            slot,
        };
        f.numeric(par)?;
        Ok(f)
    }

    /// Factors the matrix given by its upper triangle in compressed columns (rows sorted,
    /// so the diagonal comes last), eliminating the rows in stored order: for a matrix
    /// assembled in a fill-reducing order already, which spares faer a permuted copy in the
    /// symbolic and in every numeric factorization.
    pub fn from_upper_in_order(a: SparseColMat<usize, f64>, par: Par) -> Result<SpdFactor, String> {
        Self::with_ordering(a, Side::Upper, SymmetricOrdering::Identity, par)
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
        Self::with_ordering(a, Side::Lower, ordering, par)
    }

    fn with_ordering(
        a: SparseColMat<usize, f64>,
        side: Side,
        ordering: SymmetricOrdering<'_, usize>,
        par: Par,
    ) -> Result<SpdFactor, String> {
        let symbolic =
            factorize_symbolic_cholesky(a.symbolic(), side, ordering, Default::default())
                .map_err(|e| format!("symbolic Cholesky: {e:?}"))?;
        let mut f = SpdFactor {
            values: vec![0.0; symbolic.len_val()],
            columns: None,
            gather: Vec::new(),
            dropped: Vec::new(),
            many_solves: false,
            interleaved: std::sync::OnceLock::new(),
            symbolic,
            slot: (0..a.val().len()).collect(),
            matrix: a,
            side,
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
                self.side,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| format!("Cholesky: {e:?}"))?;
        if self.many_solves {
            self.update_columns();
        }
        self.interleaved = std::sync::OnceLock::new();
        Ok(())
    }

    /// Whether faer chose its supernodal factorization (dense blocks) over the simplicial one.
    pub fn is_supernodal(&self) -> bool {
        matches!(self.symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_))
    }

    /// For each unknown, the step at which the factorization eliminates it (the inverse of
    /// the fill-reducing permutation). Eliminating the unknowns of a subgraph in this relative
    /// order fills no more than the whole factor does on that subgraph.
    pub fn elimination_position(&self) -> Vec<usize> {
        match self.symbolic.perm() {
            Some(perm) => perm.arrays().1.to_vec(),
            None => (0..self.dim()).collect(),
        }
    }

    /// Number of unknowns.
    pub fn dim(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Number of stored entries of the factor (a measure of the cost of one solve).
    pub fn factor_nnz(&self) -> usize {
        self.values.len()
    }
}
