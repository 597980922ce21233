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

/// A simplicial factor `L` for `SpdFactor::solve3`, its strictly lower part twice: by
/// columns (for `Lᵀ`) and by rows (for `L`), so that both triangular solves gather (a sum
/// per unknown) instead of scattering updates; row indices as `u32` (12 bytes an entry
/// instead of 16), the diagonal apart.
pub(super) struct Compact {
    col: Vec<u32>,
    row: Vec<u32>,
    val: Vec<f64>,
    /// The same entries by rows: `row_ptr[i]..row_ptr[i + 1]` index `row_col`/`row_val`.
    row_ptr: Vec<u32>,
    row_col: Vec<u32>,
    row_val: Vec<f64>,
    diag: Vec<f64>,
    /// `perm[k]`: the unknown eliminated `k`-th (empty for the identity).
    perm: Vec<u32>,
}

/// `s - Σ v_k y[i_k]` over the entries `(i_k, v_k)`, in four interleaved partial sums (the
/// sum is bound by the latency of its additions, not by memory).
#[inline(always)]
fn gather(s: [f64; 3], idx: &[u32], val: &[f64], y: &[[f64; 3]]) -> [f64; 3] {
    let mut acc = [[0.0f64; 3]; 4];
    acc[0] = s;
    let (ip, vp) = (idx.chunks_exact(4), val.chunks_exact(4));
    let (ir, vr) = (ip.remainder(), vp.remainder());
    for (i, v) in ip.zip(vp) {
        for u in 0..4 {
            let a = y[i[u] as usize];
            for ch in 0..3 {
                acc[u][ch] -= v[u] * a[ch];
            }
        }
    }
    for (u, (&i, &v)) in ir.iter().zip(vr).enumerate() {
        let a = y[i as usize];
        for ch in 0..3 {
            acc[u][ch] -= v * a[ch];
        }
    }
    std::array::from_fn(|ch| (acc[0][ch] + acc[1][ch]) + (acc[2][ch] + acc[3][ch]))
}

impl SpdFactor {
    /// The `Compact` copy of a simplicial factor (made at the first call after each
    /// factorization); `None` for a supernodal one.
    fn compact(&self) -> Option<&Compact> {
        let SymbolicCholeskyRaw::Simplicial(sym) = self.symbolic.raw() else {
            return None;
        };
        if self.values.len() >= u32::MAX as usize {
            return None;
        }
        Some(self.interleaved.get_or_init(|| {
            let l = SparseColMatRef::new(sym.factor(), &self.values);
            let n = l.ncols();
            let m = self.values.len() - n;
            let mut c = Compact {
                col: Vec::with_capacity(n + 1),
                row: Vec::with_capacity(m),
                val: Vec::with_capacity(m),
                row_ptr: vec![0; n + 1],
                row_col: vec![0; m],
                row_val: vec![0.0; m],
                diag: Vec::with_capacity(n),
                perm: self.symbolic.perm().map_or(Vec::new(), |p| {
                    p.arrays().0.iter().map(|&v| v as u32).collect()
                }),
            };
            c.col.push(0);
            for j in 0..n {
                // the diagonal is the first entry of its column
                let (rows, vals) = (l.row_idx_of_col_raw(j), l.val_of_col(j));
                c.diag.push(vals[0]);
                c.row.extend(rows[1..].iter().map(|&i| i as u32));
                c.val.extend_from_slice(&vals[1..]);
                c.col.push(c.row.len() as u32);
            }
            // the transpose: count per row, prefix sums, fill in column order
            for &i in &c.row {
                c.row_ptr[i as usize + 1] += 1;
            }
            for i in 0..n {
                c.row_ptr[i + 1] += c.row_ptr[i];
            }
            let mut next = c.row_ptr.clone();
            for j in 0..n {
                for k in c.col[j] as usize..c.col[j + 1] as usize {
                    let i = c.row[k] as usize;
                    let at = next[i] as usize;
                    (c.row_col[at], c.row_val[at]) = (j as u32, c.val[k]);
                    next[i] += 1;
                }
            }
            c
        }))
    }

    /// Solves `A X = B` in place for exactly three right-hand sides (the columns of `rhs`,
    /// e.g. the colour channels of an image), their values interleaved in `work` so that
    /// each entry of a simplicial factor is read once per triangular solve, on one thread.
    /// Returns `false`, having done nothing, for a supernodal factor or another column count.
    ///
    /// On the course's Poisson mask (14.9k unknowns, AMD, 294k entries) this takes 0.47-0.49
    /// ms, faer's solve of the three columns on one core 0.62-0.63 (docs/image.md).
    pub fn solve3(&self, mut rhs: MatMut<'_, f64>, work: &mut Vec<[f64; 3]>) -> bool {
        if rhs.ncols() != 3 {
            return false;
        }
        let Some(c) = self.compact() else {
            return false;
        };
        let n = c.diag.len();
        let at = |k: usize| {
            if c.perm.is_empty() {
                k
            } else {
                c.perm[k] as usize
            }
        };
        work.clear();
        work.extend((0..n).map(|k| {
            let i = at(k);
            [rhs[(i, 0)], rhs[(i, 1)], rhs[(i, 2)]]
        }));
        let y = &mut work[..];
        // L y = P b, row by row
        for i in 0..n {
            let (a, b) = (c.row_ptr[i] as usize, c.row_ptr[i + 1] as usize);
            let s = gather(y[i], &c.row_col[a..b], &c.row_val[a..b], y);
            let d = c.diag[i];
            y[i] = [s[0] / d, s[1] / d, s[2] / d];
        }
        // Lᵀ x = y, backwards
        for j in (0..n).rev() {
            let (a, b) = (c.col[j] as usize, c.col[j + 1] as usize);
            let s = gather(y[j], &c.row[a..b], &c.val[a..b], y);
            let d = c.diag[j];
            y[j] = [s[0] / d, s[1] / d, s[2] / d];
        }
        for (k, v) in y.iter().enumerate() {
            let i = at(k);
            for (ch, &v) in v.iter().enumerate() {
                rhs[(i, ch)] = v;
            }
        }
        true
    }
}
