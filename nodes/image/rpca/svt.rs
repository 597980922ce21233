//! Singular value thresholding D_τ(X) = U max(Σ - τ, 0) Vᵀ (Cai, Candès & Shen 2010), the
//! proximal operator of τ ||·||_*, as the RPCA iteration (`admm.rs`) calls it once per step.
//!
//! Through the eigendecomposition of the smaller Gram matrix G (XᵀX or XXᵀ): its eigenvalues
//! are σ², its eigenvectors V (or U), and D_τ(X) = X V diag(1 - τ/σ) Vᵀ over σ > τ. On
//! 500 x 500 this costs about 0.45 of faer's thin SVD. Squaring costs accuracy only at singular
//! values far below the largest (absolute error ε σ_max² in σ²); the kept ones are above τ, and
//! the RPCA tests recover L and S to 1e-6 with it. Falls back to the SVD if the eigensolver
//! fails.
//!
//! Warm start ([`Thresholder`]): once few directions are kept, the next step's are found by
//! subspace iteration with Rayleigh–Ritz (Saad, "Numerical Methods for Large Eigenvalue
//! Problems", 2011, §5.2) started from the previous step's vectors, which ADMM changes little.
//! The result is still certified, not hoped for: the number k of eigenvalues of G above τ² is
//! the number of positive eigenvalues of G - τ² I, read off its L B Lᵀ (Bunch–Kaufman)
//! factorization by Sylvester's law of inertia; and by the Kahan–Parlett–Jiang theorem
//! (Parlett, "The Symmetric Eigenvalue Problem", Thm 11.5.1) k orthonormal Ritz vectors with
//! residual R = G U - U Θ lie within ||R||₂ of k distinct eigenvalues. When all k Ritz values
//! exceed τ² by more than ||R||_F, those are the k kept eigenvalues, and by Davis and Kahan's
//! sin Θ theorem (1970) the Ritz vectors span the kept eigenspace to within an angle of
//! ||R||_F / (θ_k - τ²), which must be below 1e-10; otherwise the full eigendecomposition runs.

use crate::image_svd::svd::randomized::gaussian_matrix;
use crate::image_svd::svd::SvdError;
use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::evd::{
    self_adjoint_evd, self_adjoint_evd_scratch, ComputeEigenvectors, SelfAdjointEvdParams,
};
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{matmul as tri_matmul, BlockStructure};
use faer::prelude::{default, Reborrow, ReborrowMut};
use faer::{Accum, Mat, MatMut, MatRef, Par};

/// Warm starts are tried while at most this fraction of the directions was kept last step
/// (1 / 8): above it the block's products and the factorization of G - τ² I cost about what
/// the full eigendecomposition does.
const WARM_FRACTION: usize = 8;
/// Extra columns in the subspace beyond the kept directions.
const OVERSAMPLE: usize = 8;
/// Filter rounds before giving up on the warm start.
const MAX_STEPS: usize = 4;
/// Highest degree of one Chebyshev filter.
const MAX_DEGREE: usize = 12;
/// The tridiagonal reduction inside the eigensolver runs its trailing matrix-vector products
/// on several threads only while more than this many rows remain (faer's default: 313). On
/// two cores, 500 x 500 took 5.2 ms on one thread and 8.6-9.8 ms on two, 1000 x 1000 50 and
/// 57 ms, 1500 x 1500 196 and 164 ms (faer 0.24, 2026-12-02, scratch timing of
/// `tridiag_in_place`); the rest of the eigensolver keeps both threads.
const TRIDIAG_PAR_MIN: usize = 1000;
/// Accept when the Davis–Kahan bound ||R||_F / (θ_k - τ²) on the sine of the angle between
/// the Ritz subspace and the kept eigenspace is below this.
const ANGLE_TOL: f64 = 1e-10;

/// D_τ with memory of the previous call's kept directions, for a sequence of nearby matrices
/// of one shape (the ADMM iterates). It also keeps its buffers (the Gram matrix, the
/// eigensolver's output and workspace, the filter): fresh pages for them were about a twentieth
/// of a 500 x 500 step.
pub struct Thresholder {
    /// Kept eigenvectors of the previous Gram matrix (d x k), while few enough for a warm start.
    prev: Option<Mat<f64>>,
    /// The Gram matrix, reused between calls.
    gram: Mat<f64>,
    /// The full eigensolver's eigenvectors (d x d) and eigenvalues.
    vecs: Mat<f64>,
    vals: Diag<f64>,
    /// The eigensolver's workspace.
    stack: MemBuffer,
    stack_bytes: usize,
    /// The d x d filter of the many-directions branch of `apply_filter`.
    filter: Mat<f64>,
    /// The warm start's factorization of G - τ² I.
    inertia: Inertia,
    /// Calls answered by the warm start and by the full eigendecomposition.
    pub warm_calls: usize,
    /// See `warm_calls`.
    pub full_calls: usize,
}

impl Default for Thresholder {
    fn default() -> Self {
        Thresholder {
            prev: None,
            gram: Mat::zeros(0, 0),
            vecs: Mat::zeros(0, 0),
            vals: Diag::zeros(0),
            stack: MemBuffer::new(StackReq::EMPTY),
            stack_bytes: 0,
            filter: Mat::zeros(0, 0),
            inertia: Inertia::default(),
            warm_calls: 0,
            full_calls: 0,
        }
    }
}

/// D_τ(X) and the number of singular values above τ, without a warm start.
pub fn singular_value_threshold(
    x: MatRef<'_, f64>,
    tau: f64,
) -> Result<(Mat<f64>, usize), SvdError> {
    Thresholder::default().threshold(x, tau)
}

impl Thresholder {
    /// D_τ(X) and the rank kept (singular values above τ).
    pub fn threshold(
        &mut self,
        x: MatRef<'_, f64>,
        tau: f64,
    ) -> Result<(Mat<f64>, usize), SvdError> {
        let mut out = Mat::zeros(x.nrows(), x.ncols());
        let k = self.threshold_into(x, tau, &mut out)?;
        Ok((out, k))
    }

    /// D_τ(X) written into `out` (resized if its shape differs), and the rank kept.
    pub fn threshold_into(
        &mut self,
        x: MatRef<'_, f64>,
        tau: f64,
        out: &mut Mat<f64>,
    ) -> Result<usize, SvdError> {
        let (m, n) = x.shape();
        if out.shape() != (m, n) {
            *out = Mat::zeros(m, n);
        }
        let tall = m >= n;
        let d = m.min(n);
        let par = faer::get_global_parallelism();
        if self.gram.shape() != (d, d) {
            self.gram = Mat::zeros(d, d);
            self.prev = None;
        }
        let (a, b) = if tall {
            (x.transpose(), x)
        } else {
            (x, x.transpose())
        };
        // only G's lower triangle: the eigensolver and the factorization read no more
        tri_matmul(
            self.gram.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Replace,
            a,
            BlockStructure::Rectangular,
            b,
            BlockStructure::Rectangular,
            1.0,
            par,
        );
        let start = self
            .prev
            .as_ref()
            .filter(|v| v.ncols() > 0 && WARM_FRACTION * (v.ncols() + OVERSAMPLE) <= d);
        let warm = start.and_then(|v| {
            // the warm start multiplies by G: the whole matrix (the eigensolver below still
            // reads only the lower triangle)
            mirror_lower(&mut self.gram);
            warm_eigen(
                self.gram.as_ref(),
                tau * tau,
                v.as_ref(),
                &mut self.inertia,
                par,
            )
        });
        let k = match warm {
            Some((sigma2, mut v)) => {
                self.warm_calls += 1;
                // few directions (at most d / 4): the filter does not scale v in place
                let f = &mut self.filter;
                apply_filter(x, v.as_mut(), &sigma2, tau, tall, f, out.as_mut(), par);
                self.prev = Some(v);
                sigma2.len()
            }
            None => {
                self.full_calls += 1;
                if !self.full_eigen(par) {
                    self.prev = None;
                    let (l, k) = svt_by_svd(x, tau)?;
                    *out = l;
                    return Ok(k);
                }
                let lambda = self.vals.column_vector();
                // eigenvalues ascending: the kept ones are the last k
                let k = (0..d).rev().take_while(|&i| lambda[i] > tau * tau).count();
                let sigma2: Vec<f64> = (d - k..d).map(|i| lambda[i]).collect();
                let v = self.vecs.subcols_mut(d - k, k);
                // remembered only when the next step could start from it
                self.prev = (WARM_FRACTION * (k + OVERSAMPLE) <= d).then(|| v.to_owned());
                apply_filter(
                    x,
                    v,
                    &sigma2,
                    tau,
                    tall,
                    &mut self.filter,
                    out.as_mut(),
                    par,
                );
                k
            }
        };
        Ok(k)
    }

    /// The eigendecomposition of the Gram matrix (lower triangle) into the kept buffers;
    /// false if the eigensolver failed.
    fn full_eigen(&mut self, par: Par) -> bool {
        let d = self.gram.nrows();
        if self.vecs.shape() != (d, d) {
            self.vecs = Mat::zeros(d, d);
            self.vals = Diag::zeros(d);
        }
        let mut params: faer::Spec<SelfAdjointEvdParams, f64> = default();
        params.config.tridiag.par_threshold = TRIDIAG_PAR_MIN * TRIDIAG_PAR_MIN / 2;
        let req = self_adjoint_evd_scratch::<f64>(d, ComputeEigenvectors::Yes, par, params);
        if req.size_bytes() > self.stack_bytes {
            self.stack = MemBuffer::new(req);
            self.stack_bytes = req.size_bytes();
        }
        self_adjoint_evd(
            self.gram.as_ref(),
            self.vals.as_mut(),
            Some(self.vecs.as_mut()),
            par,
            MemStack::new(&mut self.stack),
            params,
        )
        .is_ok()
    }
}

/// X V diag(1 - τ/σ) Vᵀ (tall) or V diag(1 - τ/σ) Vᵀ X (wide), into `out`. When most
/// directions are kept (k > 2d/3 of d), the d x d filter F = W Wᵀ with
/// W = V diag(√(1 - τ/σ)) (V scaled in place) is formed in `filter` as a lower triangle and
/// mirrored, and X F costs one product: d² k / 2 + m d² multiply-adds instead of 2 m d k.
#[allow(clippy::too_many_arguments)]
fn apply_filter(
    x: MatRef<'_, f64>,
    mut v: MatMut<'_, f64>,
    sigma2: &[f64],
    tau: f64,
    tall: bool,
    filter: &mut Mat<f64>,
    out: MatMut<'_, f64>,
    par: Par,
) {
    let mut out = out;
    let (d, k) = v.shape();
    if k == 0 {
        out.fill(0.0);
        return;
    }
    let shrink = |j: usize| 1.0 - tau / sigma2[j].sqrt();
    if 3 * k > 2 * d {
        for (j, col) in v.rb_mut().col_iter_mut().enumerate() {
            let w = shrink(j).sqrt();
            col.iter_mut().for_each(|e| *e *= w);
        }
        if filter.shape() != (d, d) {
            *filter = Mat::zeros(d, d);
        }
        tri_matmul(
            filter.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Replace,
            v.rb(),
            BlockStructure::Rectangular,
            v.rb().transpose(),
            BlockStructure::Rectangular,
            1.0,
            par,
        );
        mirror_lower(filter);
        let (a, b) = if tall {
            (x, filter.as_ref())
        } else {
            (filter.as_ref(), x)
        };
        matmul_by_row_blocks(out, a, b, par);
        return;
    }
    let v = v.rb();
    let scaled = Mat::from_fn(d, k, |i, j| v[(i, j)] * shrink(j));
    if tall {
        let mut xv = Mat::zeros(x.nrows(), k);
        matmul_by_row_blocks(xv.as_mut(), x, v, par);
        matmul(out, Accum::Replace, xv, scaled.transpose(), 1.0, par);
    } else {
        matmul(out, Accum::Replace, scaled, v.transpose() * x, 1.0, par);
    }
}

/// Rows of `out` per product call in `matmul_by_row_blocks`. faer's one-thread product
/// (private-gemm-x86's AVX-512 kernels) slows down when the output's rows and the inner
/// dimension are both between about 416 and 511: on the AVX-512 Xeon of 2026-12-02, 500 x 500
/// x 500 ran at 48-57 GFlop/s, 250 x 500 x 500 and 512 x 512 x 512 at 95-102 (scratch timing).
/// With the 500 x 500 filter product in blocks of at most 320 rows, the filter (W Wᵀ and X F)
/// took 4.85 instead of 6.6 ms per step.
const ROW_BLOCK: usize = 320;

/// `out = a b`, by blocks of at most `ROW_BLOCK` rows of `out` and `a`.
fn matmul_by_row_blocks(
    mut out: MatMut<'_, f64>,
    a: MatRef<'_, f64>,
    b: MatRef<'_, f64>,
    par: Par,
) {
    let m = a.nrows();
    let blocks = m.div_ceil(ROW_BLOCK).max(1);
    let mut r0 = 0;
    for i in 0..blocks {
        let r1 = m * (i + 1) / blocks;
        matmul(
            out.rb_mut().subrows_mut(r0, r1 - r0),
            Accum::Replace,
            a.subrows(r0, r1 - r0),
            b,
            1.0,
            par,
        );
        r0 = r1;
    }
}

/// Copies the strict lower triangle of a square matrix onto the upper one.
fn mirror_lower(f: &mut Mat<f64>) {
    for j in 0..f.ncols() {
        for i in 0..j {
            f[(i, j)] = f[(j, i)];
        }
    }
}

/// The eigenpairs of the symmetric `g` (both triangles) with eigenvalues above
/// `threshold`, by subspace iteration from `start`, certified as the module comment says;
/// `None` when the certificate is not reached (the caller then runs the full eigensolver).
/// Eigenvalues ascending, eigenvectors as columns.
fn warm_eigen(
    g: MatRef<'_, f64>,
    threshold: f64,
    start: MatRef<'_, f64>,
    inertia: &mut Inertia,
    par: Par,
) -> Option<(Vec<f64>, Mat<f64>)> {
    let d = g.nrows();
    let k = inertia.eigenvalues_above(g, threshold, par)?;
    if k == 0 {
        return Some((Vec::new(), Mat::zeros(d, 0)));
    }
    let b = (k.max(start.ncols()) + OVERSAMPLE).min(d);
    if WARM_FRACTION * b > 2 * d {
        return None;
    }
    // the previous directions, then Gaussian columns (fixed seed: runs are repeatable)
    let extra = gaussian_matrix(d, b - start.ncols().min(b), 0x5EED);
    let q0 = Mat::from_fn(d, b, |i, j| {
        if j < start.ncols() {
            start[(i, j)]
        } else {
            extra[(i, j - start.ncols())]
        }
    });
    let mut q = q0.qr().compute_thin_Q();
    for _ in 0..MAX_STEPS {
        let mut gq = Mat::<f64>::zeros(d, b);
        matmul_by_row_blocks(gq.as_mut(), g, q.as_ref(), par);
        // Rayleigh–Ritz on span(q)
        let h = q.transpose() * &gq;
        let h = Mat::from_fn(b, b, |i, j| 0.5 * (h[(i, j)] + h[(j, i)]));
        let eig = h.self_adjoint_eigen(faer::Side::Lower).ok()?;
        let (theta, w) = (eig.S().column_vector(), eig.U());
        let top = w.subcols(b - k, k);
        let u = &q * top;
        let gu = &gq * top;
        let mut r2 = 0.0;
        for j in 0..k {
            let t = theta[b - k + j];
            for i in 0..d {
                let r = gu[(i, j)] - t * u[(i, j)];
                r2 += r * r;
            }
        }
        let r = r2.sqrt();
        // θ_k - r bounds the k-th eigenvalue from below (Kahan–Parlett–Jiang); the rest are
        // at most τ² (inertia), so θ_k - τ² bounds the separation in Davis–Kahan's theorem
        let gap = theta[b - k] - threshold;
        if gap > r && r <= ANGLE_TOL * gap {
            let values = (b - k..b).map(|i| theta[i]).collect();
            return Some((values, u));
        }
        if gap <= 0.0 {
            return None;
        }
        // amplify the kept directions: a Chebyshev polynomial of G that stays within ±1 on
        // [0, τ²], where every unwanted eigenvalue lies, and is at least T_m(a) at θ_k, which
        // cuts tan Θ by that factor; m from the angle still to go
        let a = 2.0 * theta[b - k] / threshold - 1.0;
        let angle = if gap > r { r / gap } else { 1.0 };
        let m = ((angle / (0.25 * ANGLE_TOL)).acosh() / a.acosh()).ceil();
        if m.is_nan() || m > MAX_DEGREE as f64 {
            // too close to the threshold for a short filter: the full eigensolver is cheaper
            return None;
        }
        let m = (m as usize).max(1);
        let ritz = &q * w;
        let g_ritz = &gq * w;
        let filtered = chebyshev_filter(g, ritz, g_ritz, threshold, m, par);
        q = filtered.qr().compute_thin_Q();
    }
    None
}

/// T_m((G - c I) / e) Z with c = e = τ²/2 (the interval [0, τ²] mapped onto [-1, 1]), by the
/// three-term recurrence T_{j+1} = 2 x T_j - T_{j-1} (Zhou & Saad 2007, "A Chebyshev–Davidson
/// algorithm", Alg. 3.1, unscaled: m is small); `gz` is G Z, already known. Columns longer
/// than 1 are then scaled to unit length, to keep them comparable before the QR.
fn chebyshev_filter(
    g: MatRef<'_, f64>,
    z: Mat<f64>,
    gz: Mat<f64>,
    threshold: f64,
    m: usize,
    par: Par,
) -> Mat<f64> {
    let (d, b) = z.shape();
    let ce = 0.5 * threshold;
    let mut prev = z;
    let mut cur = Mat::from_fn(d, b, |i, j| (gz[(i, j)] - ce * prev[(i, j)]) / ce);
    let mut next = Mat::<f64>::zeros(d, b);
    for _ in 1..m {
        matmul_by_row_blocks(next.as_mut(), g, cur.as_ref(), par);
        for j in 0..b {
            for i in 0..d {
                next[(i, j)] = 2.0 * (next[(i, j)] - ce * cur[(i, j)]) / ce - prev[(i, j)];
            }
        }
        std::mem::swap(&mut prev, &mut cur);
        std::mem::swap(&mut cur, &mut next);
    }
    for j in 0..b {
        let norm = cur.col(j).norm_l2();
        if norm > 1.0 {
            cur.col_mut(j).iter_mut().for_each(|v| *v /= norm);
        }
    }
    cur
}

/// The number of eigenvalues of the symmetric `g` above `threshold`; see
/// [`Inertia::eigenvalues_above`].
#[cfg(test)]
fn eigenvalues_above(g: MatRef<'_, f64>, threshold: f64) -> Option<usize> {
    Inertia::default().eigenvalues_above(g, threshold, Par::Seq)
}

/// The L B Lᵀ factorization's buffers, kept between warm starts: the count used to copy G
/// twice into fresh d x d matrices, each about 0.7 ms of page faults at d = 500 (scratch
/// timing), in a count of about 2 ms.
struct Inertia {
    a: Mat<f64>,
    subdiag: Diag<f64>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    stack: MemBuffer,
}

impl Default for Inertia {
    fn default() -> Self {
        Inertia {
            a: Mat::zeros(0, 0),
            subdiag: Diag::zeros(0),
            perm: Vec::new(),
            perm_inv: Vec::new(),
            stack: MemBuffer::new(StackReq::EMPTY),
        }
    }
}

impl Inertia {
    /// The number of eigenvalues of the symmetric `g` above `threshold`: the positive
    /// eigenvalues of g - threshold I, counted on the 1x1 and 2x2 blocks of its L B Lᵀ
    /// factorization (Sylvester's law of inertia). `None` if a pivot is not finite.
    fn eigenvalues_above(&mut self, g: MatRef<'_, f64>, threshold: f64, par: Par) -> Option<usize> {
        use faer::linalg::cholesky::lblt::factor::{cholesky_in_place, cholesky_in_place_scratch};
        let d = g.nrows();
        if self.a.shape() != (d, d) {
            self.a = Mat::zeros(d, d);
            self.subdiag = Diag::zeros(d);
            self.perm = vec![0; d];
            self.perm_inv = vec![0; d];
            let req = cholesky_in_place_scratch::<usize, f64>(d, par, default());
            self.stack = MemBuffer::new(req);
        }
        self.a.copy_from(g);
        for j in 0..d {
            self.a[(j, j)] -= threshold;
        }
        cholesky_in_place(
            self.a.as_mut(),
            self.subdiag.as_mut(),
            &mut self.perm,
            &mut self.perm_inv,
            par,
            MemStack::new(&mut self.stack),
            default(),
        );
        let sub = self.subdiag.column_vector();
        let diag = |i: usize| self.a[(i, i)];
        let mut positive = 0;
        let mut i = 0;
        while i < d {
            if i + 1 < d && sub[i] != 0.0 {
                // a 2x2 block [[a, s], [s, c]]: det < 0 means one eigenvalue of each sign
                let (a, s, c) = (diag(i), sub[i], diag(i + 1));
                let det = a * c - s * s;
                if !det.is_finite() || !(a + c).is_finite() {
                    return None;
                }
                positive += if det < 0.0 {
                    1
                } else if a + c > 0.0 {
                    2
                } else {
                    0
                };
                i += 2;
            } else {
                if !diag(i).is_finite() {
                    return None;
                }
                positive += usize::from(diag(i) > 0.0);
                i += 1;
            }
        }
        Some(positive)
    }
}

/// `singular_value_threshold` through faer's thin SVD.
pub fn svt_by_svd(x: MatRef<'_, f64>, tau: f64) -> Result<(Mat<f64>, usize), SvdError> {
    let svd = x.thin_svd().map_err(SvdError::NoConvergence)?;
    let s = svd.S().column_vector();
    let k = (0..s.nrows()).take_while(|&i| s[i] > tau).count();
    if k == 0 {
        return Ok((Mat::zeros(x.nrows(), x.ncols()), 0));
    }
    let u = svd.U();
    let us = Mat::from_fn(x.nrows(), k, |i, j| u[(i, j)] * (s[j] - tau));
    Ok((us * svd.V().subcols(0, k).transpose(), k))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gram_threshold_equals_the_svd_threshold() {
        // tall and wide, ranks kept from none to all
        for (m, n) in [(40, 25), (25, 40), (30, 30)] {
            let x = Mat::from_fn(m, n, |i, j| {
                (((i * 7919 + j * 104_729 + i * j * 31) % 1000) as f64) / 1000.0 - 0.5
            });
            for tau in [0.0, 0.05, 0.5, 2.0, 100.0] {
                let (a, ka) = singular_value_threshold(x.as_ref(), tau).unwrap();
                let (b, kb) = svt_by_svd(x.as_ref(), tau).unwrap();
                assert_eq!(ka, kb, "{m}x{n} tau {tau}");
                let scale = x.norm_max();
                assert!((&a - &b).norm_max() < 1e-10 * scale, "{m}x{n} tau {tau}");
            }
        }
    }

    #[test]
    fn row_blocks_give_the_plain_product() {
        for m in [1, 319, 320, 321, 700] {
            let (a, b) = (gaussian_matrix(m, 40, 7), gaussian_matrix(40, 30, 8));
            let mut out = Mat::zeros(m, 30);
            matmul_by_row_blocks(out.as_mut(), a.as_ref(), b.as_ref(), Par::Seq);
            assert!((&out - &a * &b).norm_max() < 1e-12, "{m} rows");
        }
    }

    #[test]
    fn inertia_counts_the_eigenvalues_above_a_threshold() {
        let a = gaussian_matrix(60, 60, 3);
        let g = a.transpose() * &a;
        let eig = g.self_adjoint_eigen(faer::Side::Lower).unwrap();
        let lambda = eig.S().column_vector();
        for t in [-1.0, 0.5, 10.0, 60.0, 150.0, 1e6] {
            let expected = (0..60).filter(|&i| lambda[i] > t).count();
            assert_eq!(
                eigenvalues_above(g.as_ref(), t),
                Some(expected),
                "threshold {t}"
            );
        }
    }

    /// A slowly changing rank-6 matrix plus noise below τ, as in ADMM's low-rank phase: after
    /// the first call the warm start answers, and every answer equals the SVD's; a step whose
    /// rank jumps past the warm start's reach still comes out right (full eigensolver).
    #[test]
    fn warm_start_equals_the_svd_threshold_on_a_sequence() {
        for (m, n) in [(200, 160), (160, 200)] {
            let (a, b) = (gaussian_matrix(m, 6, 1), gaussian_matrix(n, 6, 2));
            let wide = gaussian_matrix(m, 40, 4) * gaussian_matrix(n, 40, 5).transpose();
            let mut svt = Thresholder::default();
            for t in 0..7 {
                let noise = gaussian_matrix(m, n, 10 + t as u64);
                let mut x = &a * b.transpose() * (1.0 + 0.05 * t as f64) + noise * 0.01;
                if t == 4 {
                    x += &wide;
                }
                let tau = 1.0;
                let (l, k) = svt.threshold(x.as_ref(), tau).unwrap();
                let (l_ref, k_ref) = svt_by_svd(x.as_ref(), tau).unwrap();
                assert_eq!(k, k_ref, "{m}x{n} step {t}");
                assert!(
                    (&l - &l_ref).norm_max() < 1e-9 * x.norm_max(),
                    "{m}x{n} step {t}"
                );
            }
            // steps 1-3 and 6 warm; 0, 4 (rank jump) and 5 (after it, 40 kept) full
            assert_eq!((svt.warm_calls, svt.full_calls), (4, 3), "{m}x{n}");
        }
    }
}
