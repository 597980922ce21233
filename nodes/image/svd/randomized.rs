//! Randomized SVD (Halko, Martinsson & Tropp 2011, "Finding structure with randomness"):
//! Alg. 4.4, randomized subspace iteration, finds an orthonormal basis Q of (nearly) the
//! range of A from l = k + p random samples, re-orthonormalizing by QR after every product
//! with A or A^T so the columns do not all collapse onto the dominant singular vector; then
//! Alg. 5.1 takes the SVD of the small matrix B = Q^T A (l x n) and lifts U = Q Ũ.

use super::{truncated, Factors, RandomizedParams, SvdError};
use faer::{Mat, MatRef};

/// SplitMix64 (Steele, Lea & Flood 2014): a small, seedable generator for the test matrix.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1].
    fn uniform(&mut self) -> f64 {
        ((self.next() >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }

    /// Standard normal by Box–Muller.
    fn gaussian(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// The orthonormal factor of the thin QR of `y`.
fn orthonormalize(y: &Mat<f64>) -> Mat<f64> {
    y.qr().compute_thin_Q()
}

/// An n x l standard Gaussian matrix Ω from `seed`.
pub fn gaussian_matrix(n: usize, l: usize, seed: u64) -> Mat<f64> {
    let mut g = SplitMix(seed);
    let mut m = Mat::zeros(n, l);
    for j in 0..l {
        for i in 0..n {
            m[(i, j)] = g.gaussian();
        }
    }
    m
}

/// Alg. 4.4: an m x l matrix Q with orthonormal columns whose range approximates A's,
/// l = min(k + oversample, min(m, n)), after `power_iterations` rounds of
/// Ỹ = A^T Q, Q̃ = qr(Ỹ), Y = A Q̃, Q = qr(Y).
pub fn range_finder(a: MatRef<'_, f64>, k: usize, p: RandomizedParams) -> Mat<f64> {
    let (m, n) = a.shape();
    let l = (k + p.oversample).min(m.min(n)).max(1);
    let omega = gaussian_matrix(n, l, p.seed);
    let mut q = orthonormalize(&(a * &omega));
    for _ in 0..p.power_iterations {
        let qt = orthonormalize(&(a.transpose() * &q));
        q = orthonormalize(&(a * &qt));
    }
    q
}

/// The leading k singular triplets of `a`, estimated from a sketch of k + oversample
/// columns (Alg. 4.4 then Alg. 5.1). All l computed triplets are returned; the caller keeps
/// the first k.
pub fn randomized_svd(
    a: MatRef<'_, f64>,
    k: usize,
    p: RandomizedParams,
) -> Result<Factors, SvdError> {
    if a.nrows() == 0 || a.ncols() == 0 {
        return Err(SvdError::Empty);
    }
    let q = range_finder(a, k, p);
    let b = q.transpose() * a; // l x n
    let small = truncated::thin_svd(b.as_ref())?;
    Ok(Factors {
        u: &q * &small.u,
        s: small.s,
        v: small.v,
    })
}
