//! A sparse symmetric positive definite system factored once (faer's sparse Cholesky) and
//! solved for several right-hand sides per call.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::supernodal::{SupernodalLltRef, SymbolicSupernodalCholesky};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_lower_triangular_transpose_in_place,
};
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat, Triplet};
use faer::{Conj, Mat, MatMut, Par, Side};

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
            columns: None,
            gather: Vec::new(),
            dropped: Vec::new(),
            many_solves: false,
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
        Ok(())
    }

    /// Prepares for many solves with this factor (and its refactorizations): a supernodal
    /// factor is copied into compressed columns, now and after every refactorization. The
    /// first copy walks and allocates the whole factor (on nefertiti_front's Tutte system it
    /// cost more than the one solve it would speed up); later ones only gather the values.
    pub fn prepare_many_solves(&mut self) {
        self.many_solves = true;
        self.update_columns();
    }

    /// Refreshes `columns` after a numeric factorization (see `columns`).
    fn update_columns(&mut self) {
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

    /// The first half of `solve_in_place`: `Y = L⁻¹ P B` in place, the rows of `Y` in
    /// elimination order. With `backward_in_place` after it, `X = A⁻¹ B`; in between, the
    /// trailing rows of `Y` can be changed (see `TwoDomainFactor`).
    pub fn forward_in_place(&self, mut rhs: MatMut<'_, f64>) {
        if let Some(perm) = self.symbolic.perm() {
            let b = rhs.to_owned();
            faer::perm::permute_rows(rhs.as_mut(), b.as_ref(), perm);
        }
        self.triangular_solve(rhs, false);
    }

    /// The second half of `solve_in_place`: `X = Pᵀ L⁻ᵀ Y` in place.
    pub fn backward_in_place(&self, mut rhs: MatMut<'_, f64>) {
        self.triangular_solve(rhs.as_mut(), true);
        if let Some(perm) = self.symbolic.perm() {
            let y = rhs.to_owned();
            faer::perm::permute_rows(rhs.as_mut(), y.as_ref(), perm.inverse());
        }
    }

    /// `L⁻¹` or `L⁻ᵀ` applied in place (elimination order), through the compressed-column
    /// copy when there is one.
    fn triangular_solve(&self, rhs: MatMut<'_, f64>, transpose: bool) {
        if let Some(l) = &self.columns {
            if transpose {
                solve_lower_triangular_transpose_in_place(l.as_ref(), Conj::No, rhs, Par::Seq);
            } else {
                solve_lower_triangular_in_place(l.as_ref(), Conj::No, rhs, Par::Seq);
            }
            return;
        }
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(sym) => {
                let mut mem = MemBuffer::new(
                    self.symbolic
                        .solve_in_place_scratch::<f64>(rhs.ncols(), Par::Seq),
                );
                let l = SupernodalLltRef::new(sym, &self.values);
                let stack = MemStack::new(&mut mem);
                if transpose {
                    l.l_transpose_solve_with_conj(Conj::No, rhs, Par::Seq, stack);
                } else {
                    l.l_solve_with_conj(Conj::No, rhs, Par::Seq, stack);
                }
            }
            SymbolicCholeskyRaw::Simplicial(sym) => {
                let l = SparseColMatRef::new(sym.factor(), &self.values);
                if transpose {
                    solve_lower_triangular_transpose_in_place(l, Conj::No, rhs, Par::Seq);
                } else {
                    solve_lower_triangular_in_place(l, Conj::No, rhs, Par::Seq);
                }
            }
        }
    }

    /// Solves `A X = B` with `B` and `X` given in elimination order (row `k` for the unknown
    /// eliminated `k`-th; see `elimination_position`): the two triangular solves alone. For a
    /// caller that keeps its vectors in that order, which spares the two permuted copies of
    /// `solve_in_place`.
    pub fn solve_in_elimination_order(&self, mut rhs: MatMut<'_, f64>) {
        self.triangular_solve(rhs.as_mut(), false);
        self.triangular_solve(rhs, true);
    }

    /// Solves `A X = B` in place, every column of `rhs` at once.
    pub fn solve_in_place(&self, mut rhs: MatMut<'_, f64>) {
        if self.columns.is_some() {
            // A = Pᵀ L Lᵀ P: permute, two triangular solves, permute back
            match self.symbolic.perm() {
                Some(perm) => {
                    let mut x = Mat::<f64>::zeros(rhs.nrows(), rhs.ncols());
                    faer::perm::permute_rows(x.as_mut(), rhs.as_ref(), perm);
                    self.triangular_solve(x.as_mut(), false);
                    self.triangular_solve(x.as_mut(), true);
                    faer::perm::permute_rows(rhs.as_mut(), x.as_ref(), perm.inverse());
                }
                None => {
                    self.triangular_solve(rhs.as_mut(), false);
                    self.triangular_solve(rhs, true);
                }
            }
            return;
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Lower triplets of the 5-point Laplacian (plus a small shift) on the grid points
    /// `(i, j)` for which `keep` holds, numbered by `index`.
    fn grid_laplacian(
        k: usize,
        keep: impl Fn(usize, usize) -> bool,
        index: impl Fn(usize, usize) -> usize,
    ) -> Vec<Triplet<usize, usize, f64>> {
        let mut t = Vec::new();
        for i in 0..k {
            for j in 0..k {
                if !keep(i, j) {
                    continue;
                }
                t.push(Triplet::new(index(i, j), index(i, j), 4.01));
                for (a, b) in [(i.wrapping_sub(1), j), (i, j.wrapping_sub(1))] {
                    if a < k && b < k && keep(a, b) {
                        let (r, c) = (index(i, j), index(a, b));
                        t.push(Triplet::new(r.max(c), r.min(c), -1.0));
                    }
                }
            }
        }
        t
    }

    /// A region of a grid numbered in the whole grid's elimination order fills less than in
    /// row-major (banded) order, and `elimination_position` is the inverse permutation.
    #[test]
    fn elimination_position_orders_a_subgraph_with_little_fill() {
        let k = 40;
        let whole = SpdFactor::new(
            k * k,
            &grid_laplacian(k, |_, _| true, |i, j| i * k + j),
            Par::Seq,
        )
        .unwrap();
        let pos = whole.elimination_position();
        let mut seen = vec![false; k * k];
        for &p in &pos {
            assert!(!seen[p]);
            seen[p] = true;
        }
        // the 20 x 20 block in the middle, numbered by its rank in `pos` or row-major
        let inside = |i: usize, j: usize| (10..30).contains(&i) && (10..30).contains(&j);
        let mut region: Vec<usize> = (0..k * k).filter(|&v| inside(v / k, v % k)).collect();
        let row_major = |i: usize, j: usize| (i - 10) * 20 + (j - 10);
        region.sort_by_key(|&v| pos[v]);
        let mut rank = vec![usize::MAX; k * k];
        for (r, &v) in region.iter().enumerate() {
            rank[v] = r;
        }
        let by_rank = |i: usize, j: usize| rank[i * k + j];
        let fill = |index: &dyn Fn(usize, usize) -> usize| {
            let t = grid_laplacian(k, inside, index);
            let upper: Vec<_> = t
                .iter()
                .map(|e| Triplet::new(e.col, e.row, e.val))
                .collect();
            let a = SparseColMat::<usize, f64>::try_new_from_triplets(400, 400, &upper).unwrap();
            SpdFactor::from_upper_in_order(a, Par::Seq)
                .unwrap()
                .factor_nnz()
        };
        let (ordered, banded) = (fill(&by_rank), fill(&row_major));
        assert!(
            ordered < banded,
            "{ordered} entries in elimination order, {banded} banded"
        );
    }

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

    /// The compressed-column copy of a supernodal factor solves like faer's supernodal solve,
    /// after the first factorization and after a refactorization (gather path), and a
    /// refactorization whose padding is no longer zero rebuilds the pattern.
    #[test]
    fn column_solves_match_the_supernodal_solve() {
        // 9-point Laplacian of a k x k grid plus a small shift: large enough for supernodes
        let k = 200;
        let id = |i: usize, j: usize| i * k + j;
        let mut t = Vec::new();
        for i in 0..k {
            for j in 0..k {
                t.push(Triplet::new(id(i, j), id(i, j), 6.01));
                if i + 1 < k {
                    t.push(Triplet::new(id(i + 1, j), id(i, j), -1.0));
                    if j + 1 < k {
                        t.push(Triplet::new(id(i + 1, j + 1), id(i, j), -0.5));
                    }
                    if j > 0 {
                        t.push(Triplet::new(id(i + 1, j - 1), id(i, j), -0.5));
                    }
                }
                if j + 1 < k {
                    t.push(Triplet::new(id(i, j + 1), id(i, j), -1.0));
                }
            }
        }
        let n = k * k;
        let b = faer::Mat::<f64>::from_fn(n, 2, |i, c| ((i * 7 + c * 3) % 11) as f64 - 5.0);
        let plain = SpdFactor::new(n, &t, Par::Seq).unwrap();
        let mut fast = SpdFactor::new(n, &t, Par::Seq).unwrap();
        fast.prepare_many_solves();
        assert!(
            fast.columns.is_some(),
            "the grid should factor supernodally"
        );
        let check = |a: &SpdFactor, c: &SpdFactor| {
            let (mut x, mut y) = (b.clone(), b.clone());
            a.solve_in_place(x.as_mut());
            c.solve_in_place(y.as_mut());
            let diff = (&x - &y).norm_max();
            assert!(diff < 1e-12 * x.norm_max(), "difference {diff}");
            assert!(x.norm_max() > 0.1);
        };
        check(&plain, &fast);
        // forward then backward substitution is the whole (permuted) solve
        let (mut x, mut y) = (b.clone(), b.clone());
        plain.solve_in_place(x.as_mut());
        assert!(plain.symbolic.perm().is_some());
        plain.forward_in_place(y.as_mut());
        assert!((&x - &y).norm_max() > 0.1 * x.norm_max());
        plain.backward_in_place(y.as_mut());
        assert!((&x - &y).norm_max() < 1e-12 * x.norm_max());
        // a refactorization with another diagonal shift: values gathered again
        let t2: Vec<_> = t
            .iter()
            .map(|x| {
                Triplet::new(
                    x.row,
                    x.col,
                    if x.row == x.col { x.val + 0.5 } else { x.val },
                )
            })
            .collect();
        let plain2 = SpdFactor::new(n, &t2, Par::Seq).unwrap();
        fast.refactor(&t2, Par::Seq).unwrap();
        check(&plain2, &fast);
        // padding that is no longer zero: rebuilt, still right
        let dropped = fast.dropped.len();
        assert!(dropped > 0, "relaxed supernodes should have zero padding");
        fast.values[fast.dropped[0]] = 1.0;
        fast.update_columns();
        assert_eq!(fast.dropped.len(), dropped - 1);
        fast.refactor(&t2, Par::Seq).unwrap();
        check(&plain2, &fast);
    }
}
