//! A sparse SPD system split by a separator into two independent domains, each factored on
//! its own core, joined by the dense Schur complement of the separator (substructuring:
//! Przemieniecki 1963; the top level of George's 1973 nested dissection, where the two halves
//! of the elimination tree are independent).
//!
//! With the unknowns ordered `[domain 1, domain 2, separator]` and no coupling between the two
//! domains, `A = [A1 0 B1; 0 A2 B2; B1ᵀ B2ᵀ S]`. Each `Mi = [Ai Bi; Biᵀ S]` is a principal
//! submatrix of `A`, hence SPD, and faer factors it in stored order; the trailing block `Xi`
//! of its factor gives `Ti = Xi Xiᵀ = S - Biᵀ Ai⁻¹ Bi`, so the separator's Schur complement is
//! `T = T1 + T2 - S`, small and dense (faer's dense Cholesky). Every sparse operation is faer's.

use super::SpdFactor;
use faer::linalg::matmul::triangular::{matmul, BlockStructure};
use faer::linalg::solvers::{Llt, Solve};
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat};
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};

/// `A = [A1 0 B1; 0 A2 B2; B1ᵀ B2ᵀ S]` factored as two domains and a separator.
pub struct TwoDomainFactor {
    /// Unknowns in domain 1, domain 2; the separator is the rest.
    sizes: [usize; 2],
    /// Factors of `M1 = [A1 B1; B1ᵀ S]` and `M2 = [A2 B2; B2ᵀ S]`.
    domains: [SpdFactor; 2],
    /// `Xi`, the separator block of each domain's factor (lower triangular).
    trailing: [Mat<f64>; 2],
    /// Cholesky factorization of the separator's Schur complement `T1 + T2 - S`.
    schur: Llt<f64>,
}

impl TwoDomainFactor {
    /// Factors the matrix given by its upper triangle in compressed columns (rows sorted,
    /// diagonal last in each column), its first `n1` unknowns forming domain 1, the next `n2`
    /// domain 2 and the rest the separator, each part eliminated in stored order (for a
    /// matrix already assembled in a nested-dissection order). An entry coupling the two
    /// domains, or a matrix that is not positive definite, is an error.
    pub fn from_upper_in_order(
        a: SparseColMatRef<'_, usize, f64>,
        n1: usize,
        n2: usize,
    ) -> Result<TwoDomainFactor, String> {
        let n = a.nrows();
        if n1 + n2 > n || a.ncols() != n {
            return Err(format!(
                "domains of {n1} and {n2} unknowns in a {n}-unknown system"
            ));
        }
        let s = n - n1 - n2;
        let (col_ptr, row_idx, val) = (a.symbolic().col_ptr(), a.symbolic().row_idx(), a.val());
        // M1 keeps domain 1's columns as they are and the separator's rows of domain 1 and of
        // the separator (moved up by n2); M2 is domain 2 and the separator moved up by n1.
        let extract = |domain: usize| -> Result<SparseColMat<usize, f64>, String> {
            let (lo, hi) = if domain == 0 { (0, n1) } else { (n1, n1 + n2) };
            let shift = |r: usize| {
                if r < n1 + n2 {
                    r - lo
                } else {
                    r - n1 - n2 + (hi - lo)
                }
            };
            let mut ptr = Vec::with_capacity(hi - lo + s + 1);
            let (mut rows, mut vals) = (Vec::new(), Vec::new());
            ptr.push(0);
            for j in (lo..hi).chain(n1 + n2..n) {
                for k in col_ptr[j]..col_ptr[j + 1] {
                    let r = row_idx[k];
                    let in_domain = (lo..hi).contains(&r);
                    if j < n1 + n2 && !in_domain {
                        return Err(format!(
                            "unknowns {r} and {j} couple the two domains (not a separator)"
                        ));
                    }
                    if in_domain || r >= n1 + n2 {
                        rows.push(shift(r));
                        vals.push(val[k]);
                    }
                }
                ptr.push(rows.len());
            }
            let m = hi - lo + s;
            let sym = SymbolicSparseColMat::new_checked(m, m, ptr, None, rows);
            Ok(SparseColMat::new(sym, vals))
        };
        let factor = |domain: usize| -> Result<(SpdFactor, Mat<f64>), String> {
            let f = SpdFactor::from_upper_in_order(extract(domain)?, Par::Seq)?;
            let x = f
                .trailing_block(s)
                .ok_or("the domain factor is permuted (internal error)")?;
            Ok((f, x))
        };
        let (d1, d2) = rayon::join(|| factor(0), || factor(1));
        let ((f1, x1), (f2, x2)) = (d1?, d2?);
        // T = X1 X1ᵀ + X2 X2ᵀ - S, lower triangle only
        let mut t = Mat::<f64>::zeros(s, s);
        for j in n1 + n2..n {
            for k in col_ptr[j]..col_ptr[j + 1] {
                let r = row_idx[k];
                if r >= n1 + n2 {
                    t[(j - n1 - n2, r - n1 - n2)] = -val[k];
                }
            }
        }
        for x in [&x1, &x2] {
            matmul(
                t.as_mut(),
                BlockStructure::TriangularLower,
                Accum::Add,
                x.as_ref(),
                BlockStructure::TriangularLower,
                x.transpose(),
                BlockStructure::TriangularUpper,
                1.0,
                Par::Seq,
            );
        }
        let schur = t
            .llt(Side::Lower)
            .map_err(|e| format!("separator Schur complement: {e:?}"))?;
        Ok(TwoDomainFactor {
            sizes: [n1, n2],
            domains: [f1, f2],
            trailing: [x1, x2],
            schur,
        })
    }

    /// Number of unknowns.
    pub fn dim(&self) -> usize {
        self.domains[0].dim() + self.sizes[1]
    }

    /// Stored entries of both domain factors and the dense separator factor.
    pub fn factor_nnz(&self) -> usize {
        let s = self.trailing[0].nrows();
        self.domains[0].factor_nnz() + self.domains[1].factor_nnz() + s * (s + 1) / 2
    }

    /// Solves `A X = B` in place with one forward and one backward substitution per domain
    /// (the domains in parallel) and a dense solve on the separator between them.
    ///
    /// Forward on `[b_i; 0]` gives `[L_i⁻¹ b_i; z_i]` with `X_i z_i = -Biᵀ Ai⁻¹ b_i`, so the
    /// separator solves `T x_s = b_s + X_1 z_1 + X_2 z_2`; replacing `z_i` by `X_iᵀ x_s`, the
    /// backward substitution returns `x_s` on the separator and `A_i⁻¹ (b_i - B_i x_s)` on
    /// the domain.
    pub fn solve_in_place(&self, mut rhs: MatMut<'_, f64>) {
        let [n1, n2] = self.sizes;
        let s = self.trailing[0].nrows();
        let k = rhs.ncols();
        let range = |d: usize| if d == 0 { 0..n1 } else { n1..n1 + n2 };
        // X v or Xᵀ v for the lower triangular X of a domain
        let times = |d: usize, transpose: bool, v: MatRef<'_, f64>| {
            let x = &self.trailing[d];
            let (lhs, structure) = if transpose {
                (x.transpose(), BlockStructure::TriangularUpper)
            } else {
                (x.as_ref(), BlockStructure::TriangularLower)
            };
            let mut y = Mat::<f64>::zeros(s, k);
            matmul(
                y.as_mut(),
                BlockStructure::Rectangular,
                Accum::Replace,
                lhs,
                structure,
                v,
                BlockStructure::Rectangular,
                1.0,
                Par::Seq,
            );
            y
        };
        let forward = |d: usize| {
            let r = range(d);
            let mut y = Mat::<f64>::zeros(r.len() + s, k);
            y.as_mut()
                .subrows_mut(0, r.len())
                .copy_from(rhs.as_ref().subrows(r.start, r.len()));
            self.domains[d].forward_in_place(y.as_mut());
            let u = times(d, false, y.as_ref().subrows(r.len(), s));
            (y, u)
        };
        let ((mut y1, u1), (mut y2, u2)) = rayon::join(|| forward(0), || forward(1));
        let mut xs = rhs.as_ref().subrows(n1 + n2, s).to_owned();
        xs += u1 + u2;
        self.schur.solve_in_place(xs.as_mut());
        let backward = |d: usize, y: &mut Mat<f64>| {
            let len = range(d).len();
            let v = times(d, true, xs.as_ref());
            y.as_mut().subrows_mut(len, s).copy_from(v);
            self.domains[d].backward_in_place(y.as_mut());
        };
        rayon::join(|| backward(0, &mut y1), || backward(1, &mut y2));
        rhs.as_mut().subrows_mut(0, n1).copy_from(y1.subrows(0, n1));
        rhs.as_mut()
            .subrows_mut(n1, n2)
            .copy_from(y2.subrows(0, n2));
        rhs.subrows_mut(n1 + n2, s).copy_from(&xs);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::Triplet;

    /// A `k x k` grid Laplacian plus a small shift, ordered [left columns, right columns,
    /// middle column]: the two-domain solve matches the one-factor solve, with simplicial
    /// (small) and supernodal (large) domain factors.
    #[test]
    fn two_domains_solve_like_one_factor() {
        for (k, supernodal) in [(41, false), (151, true)] {
            assert_eq!(two_domains_on_a_grid(k), supernodal, "k = {k}");
        }
    }

    /// Returns whether the domains were factored supernodally.
    fn two_domains_on_a_grid(k: usize) -> bool {
        let mid = k / 2;
        // new index of grid vertex (i, j): left block (j < mid), right block, then column mid
        let idx = |i: usize, j: usize| -> usize {
            if j < mid {
                i * mid + j
            } else if j > mid {
                k * mid + i * (k - mid - 1) + (j - mid - 1)
            } else {
                k * (k - 1) + i
            }
        };
        let n = k * k;
        let mut upper = Vec::new();
        for i in 0..k {
            for j in 0..k {
                let a = idx(i, j);
                upper.push(Triplet::new(a, a, 4.0 + 0.01 * ((i + j) % 3) as f64));
                for (ii, jj) in [(i + 1, j), (i, j + 1)] {
                    if ii < k && jj < k {
                        let b = idx(ii, jj);
                        upper.push(Triplet::new(a.min(b), a.max(b), -1.0));
                    }
                }
            }
        }
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &upper).unwrap();
        let split =
            TwoDomainFactor::from_upper_in_order(a.as_ref(), k * mid, k * (k - mid - 1)).unwrap();
        assert_eq!(split.dim(), n);
        let whole = SpdFactor::from_upper_in_order(a.clone(), Par::Seq).unwrap();
        let b = Mat::<f64>::from_fn(n, 2, |i, c| ((i * 7 + c * 3) % 11) as f64 - 5.0);
        let (mut x, mut y) = (b.clone(), b.clone());
        whole.solve_in_place(x.as_mut());
        split.solve_in_place(y.as_mut());
        let diff = (&x - &y).norm_max();
        assert!(x.norm_max() > 0.1);
        assert!(diff < 1e-12 * x.norm_max(), "difference {diff}");
        // the residual of the split solve is small too: A = U + Uᵀ - D
        let mut dy = Mat::<f64>::zeros(n, 2);
        for t in upper.iter().filter(|t| t.row == t.col) {
            for c in 0..2 {
                dy[(t.row, c)] += t.val * y[(t.row, c)];
            }
        }
        let r = &b - a.as_ref() * &y - a.as_ref().transpose() * &y + dy;
        assert!(r.norm_max() < 1e-10, "residual {}", r.norm_max());
        // an entry coupling the domains is refused
        upper.push(Triplet::new(0, k * mid, -0.5));
        let bad = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &upper).unwrap();
        let err = TwoDomainFactor::from_upper_in_order(bad.as_ref(), k * mid, k * (k - mid - 1));
        assert!(err.is_err());
        split.domains[0].is_supernodal()
    }
}
