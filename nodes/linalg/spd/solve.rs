//! Solves with a factored `SpdFactor`: the whole solve, and its forward and backward halves.

use super::SpdFactor;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholeskyRaw};
use faer::sparse::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_lower_triangular_transpose_in_place,
};
use faer::sparse::SparseColMatRef;
use faer::{Conj, Mat, MatMut, Par};

impl SpdFactor {
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
