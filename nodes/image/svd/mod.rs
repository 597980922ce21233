//! Low-rank approximation of a matrix by its singular value decomposition (Eckart–Young: the
//! truncated SVD is the best rank-k approximation in the Frobenius norm), for `image_svd`.
//!
//! `truncated.rs` holds the exact thin SVD (faer), `randomized.rs` the randomized range
//! finder of Halko, Martinsson & Tropp 2011; this file the shared factors, the rank choice
//! by energy and the reconstruction.

pub mod randomized;
pub mod truncated;

use cgnodes_api::node::Choice;
use faer::{Mat, MatRef};

/// Why a singular value decomposition failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SvdError {
    /// The matrix has no rows or no columns.
    #[error("the matrix is empty")]
    Empty,
    /// faer's SVD reached its iteration limit.
    #[error("the SVD did not converge: {0:?}")]
    NoConvergence(faer::linalg::svd::SvdError),
}

/// How the factors are computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// faer's thin SVD of the whole matrix.
    Full,
    /// Halko, Martinsson & Tropp 2011, Alg. 4.4 (subspace iteration) then Alg. 5.1.
    Randomized,
}

impl Choice for Method {
    const CHOICES: &'static [(&'static str, Self)] =
        &[("full", Method::Full), ("randomized", Method::Randomized)];
}

/// Options of the randomized method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RandomizedParams {
    /// Extra sketch columns p beyond the target rank (Halko et al. §4.2 suggest 5 or 10).
    pub oversample: usize,
    /// Power iterations q of Alg. 4.4 (each one a product with A^T and with A).
    pub power_iterations: usize,
    /// Seed of the Gaussian test matrix.
    pub seed: u64,
}

/// Which rank to keep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Truncation {
    /// The k largest singular values.
    Rank(usize),
    /// The smallest k whose squared singular values reach this fraction of ||A||_F^2.
    Energy(f64),
}

/// A (possibly partial) SVD: A ≈ U diag(s) V^T, singular values in decreasing order.
#[derive(Clone, Debug)]
pub struct Factors {
    /// m x r left singular vectors.
    pub u: Mat<f64>,
    /// r singular values, decreasing.
    pub s: Vec<f64>,
    /// n x r right singular vectors.
    pub v: Mat<f64>,
}

/// The smallest k with s_1^2 + ... + s_k^2 >= `fraction` * `total` (`total` = ||A||_F^2,
/// the sum of all squared singular values); `None` when the given values do not reach it
/// (a partial SVD whose sketch was too small). A zero matrix needs k = 0.
pub fn energy_rank(s: &[f64], total: f64, fraction: f64) -> Option<usize> {
    let goal = fraction * total;
    let mut acc = 0.0;
    if acc >= goal {
        return Some(0);
    }
    for (i, v) in s.iter().enumerate() {
        acc += v * v;
        // a relative slack for the rounding of the two sums
        if acc >= goal * (1.0 - 1e-12) {
            return Some(i + 1);
        }
    }
    None
}

/// U_k diag(s_k) V_k^T: the rank-k reconstruction from the first k factors.
pub fn reconstruct(f: &Factors, k: usize) -> Mat<f64> {
    let k = k.min(f.s.len());
    let (m, n) = (f.u.nrows(), f.v.nrows());
    if k == 0 {
        return Mat::zeros(m, n);
    }
    let us = Mat::from_fn(m, k, |i, j| f.u[(i, j)] * f.s[j]);
    us * f.v.as_ref().subcols(0, k).transpose()
}

/// ||A||_F^2.
pub fn frobenius_sq(a: MatRef<'_, f64>) -> f64 {
    let n = a.norm_l2();
    n * n
}

/// A low-rank approximation of `a` and the rank it kept.
#[derive(Clone, Debug)]
pub struct Approximation {
    /// The rank-k matrix.
    pub matrix: Mat<f64>,
    /// k.
    pub rank: usize,
    /// The singular values computed (all of them for `Method::Full`, the sketch's for
    /// `Method::Randomized`).
    pub singular_values: Vec<f64>,
}

/// The best rank-k approximation of `a` (`Method::Full`) or its randomized estimate, with
/// k from `trunc` (a rank above min(m, n) is clamped by the caller). Errors are the SVD's.
pub fn low_rank(
    a: MatRef<'_, f64>,
    trunc: Truncation,
    method: Method,
    params: RandomizedParams,
) -> Result<Approximation, SvdError> {
    let size = a.nrows().min(a.ncols());
    let total = frobenius_sq(a);
    let (factors, rank) = match (method, trunc) {
        (Method::Full, t) => {
            let f = truncated::thin_svd(a)?;
            let k = match t {
                Truncation::Rank(k) => k.min(size),
                Truncation::Energy(e) => energy_rank(&f.s, total, e).unwrap_or(size),
            };
            (f, k)
        }
        (Method::Randomized, Truncation::Rank(k)) => {
            let k = k.min(size);
            (randomized::randomized_svd(a, k, params)?, k)
        }
        (Method::Randomized, Truncation::Energy(e)) => {
            // The sketch cannot know the singular values it did not compute, but ||A||_F^2
            // is their sum of squares: grow the sketch (doubling) until it captures `e`.
            let mut k = 16.min(size);
            loop {
                let f = randomized::randomized_svd(a, k, params)?;
                if let Some(r) = energy_rank(&f.s, total, e) {
                    break (f, r);
                }
                if k == size {
                    break (f, size);
                }
                k = (2 * k).min(size);
            }
        }
    };
    Ok(Approximation {
        matrix: reconstruct(&factors, rank),
        rank,
        singular_values: factors.s,
    })
}
