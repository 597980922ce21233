//! Robust PCA by principal component pursuit (Candès, Li, Ma & Wright 2011): split M into a
//! low-rank L and a sparse S by minimizing ||L||_* + λ ||S||_1 subject to L + S = M, with the
//! alternating direction method of multipliers on the augmented Lagrangian
//! ℓ(L, S, Y) = ||L||_* + λ||S||_1 + <Y, M - L - S> + ρ/2 ||M - L - S||_F^2
//! (Candès et al. §5, Boyd et al. 2011 §3.3 for the residuals):
//!
//! L ← D_{1/ρ}(M - S + Y/ρ)  (singular value thresholding)
//! S ← S_{λ/ρ}(M - L + Y/ρ)  (entrywise soft thresholding)
//! Y ← Y + ρ (M - L - S)
//!
//! stopping when the primal residual ||M - L - S||_F and the dual residual ρ ||S - S_prev||_F,
//! both relative to ||M||_F, are below the tolerance.

use super::svt::Thresholder;
pub use super::svt::{singular_value_threshold, svt_by_svd};
use crate::image_svd::svd::SvdError;
use faer::{Mat, MatRef};
use rayon::prelude::*;

/// Parameters of the iteration; zeros select the defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Weight of ||S||_1; 0 = 1 / sqrt(max(m, n)) (Candès et al. Thm 1.1).
    pub lambda: f64,
    /// Penalty ρ; 0 = m n / (4 ||M||_1) (Candès et al. §5).
    pub rho: f64,
    /// Bound on both relative residuals.
    pub tolerance: f64,
    /// Iteration limit.
    pub max_iterations: usize,
}

/// One iteration's record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    /// ||M - L - S||_F / ||M||_F after the iteration.
    pub primal: f64,
    /// ρ ||S - S_prev||_F / ||M||_F.
    pub dual: f64,
    /// Singular values of L above the threshold.
    pub rank: usize,
    /// Non-zero entries of S.
    pub nonzeros: usize,
    /// Whether the thresholding was answered by the warm start (`svt.rs`).
    pub warm: bool,
    /// Seconds since the decomposition started, at the end of this iteration.
    pub seconds: f64,
}

/// The decomposition and how it was reached.
#[derive(Clone, Debug)]
pub struct Decomposition {
    /// The low-rank part.
    pub low_rank: Mat<f64>,
    /// The sparse part.
    pub sparse: Mat<f64>,
    /// One record per iteration.
    pub log: Vec<Step>,
    /// Whether both residuals fell below the tolerance.
    pub converged: bool,
    /// λ and ρ used.
    pub lambda: f64,
    /// ρ used.
    pub rho: f64,
}

/// Soft thresholding S_τ(x) = sign(x) max(|x| - τ, 0), the proximal operator of τ ||·||_1.
pub fn shrink(x: f64, tau: f64) -> f64 {
    if x > tau {
        x - tau
    } else if x < -tau {
        x + tau
    } else {
        0.0
    }
}

/// Splits `m` into low-rank plus sparse parts by ADMM. `m` must be finite and non-empty (the
/// node checks); a zero matrix returns zeros at once. Errors are the SVD's.
pub fn rpca(m: MatRef<'_, f64>, p: Params) -> Result<Decomposition, SvdError> {
    let (rows, cols) = m.shape();
    let lambda = if p.lambda > 0.0 {
        p.lambda
    } else {
        1.0 / (rows.max(cols) as f64).sqrt()
    };
    let mut l1 = 0.0;
    for j in 0..cols {
        for i in 0..rows {
            l1 += m[(i, j)].abs();
        }
    }
    let norm = m.norm_l2();
    let rho = if p.rho > 0.0 {
        p.rho
    } else if l1 > 0.0 {
        (rows * cols) as f64 / (4.0 * l1)
    } else {
        1.0
    };
    let mut out = Decomposition {
        low_rank: Mat::zeros(rows, cols),
        sparse: Mat::zeros(rows, cols),
        log: Vec::new(),
        converged: norm == 0.0,
        lambda,
        rho,
    };
    if norm == 0.0 {
        return Ok(out);
    }
    let t0 = std::time::Instant::now();
    // column-major copies: M, S, Y and the next SVT argument M - S + Y/ρ, updated in one
    // pass per iteration, columns in parallel
    let mv: Vec<f64> = (0..cols)
        .flat_map(|j| (0..rows).map(move |i| m[(i, j)]))
        .collect();
    let mut s = vec![0.0; rows * cols];
    let mut y = vec![0.0; rows * cols];
    let mut arg = mv.clone();
    let (s_tau, inv_rho) = (lambda / rho, 1.0 / rho);
    let mut svt = Thresholder::default();
    for _ in 0..p.max_iterations {
        // L-step: SVT of M - S + Y/ρ
        let warm_before = svt.warm_calls;
        let x = MatRef::from_column_major_slice(&arg, rows, cols);
        let rank = svt.threshold_into(x, inv_rho, &mut out.low_rank)?;
        let l = &out.low_rank;
        // S-step, dual update, residuals and the next argument; per-column sums added in
        // column order so the stopping test does not depend on the thread count
        let sums: Vec<(f64, f64, usize)> = s
            .par_chunks_mut(rows)
            .zip(y.par_chunks_mut(rows))
            .zip(arg.par_chunks_mut(rows))
            .enumerate()
            .with_min_len(8)
            .map(|(j, ((sc, yc), ac))| {
                let (mc, lc) = (&mv[j * rows..(j + 1) * rows], l.col(j));
                let (mut ds, mut r2, mut nonzeros) = (0.0, 0.0, 0usize);
                for i in 0..rows {
                    let (mij, lij) = (mc[i], lc[i]);
                    let si = shrink(mij - lij + inv_rho * yc[i], s_tau);
                    let d = si - sc[i];
                    ds += d * d;
                    sc[i] = si;
                    nonzeros += usize::from(si != 0.0);
                    let r = mij - lij - si;
                    r2 += r * r;
                    yc[i] += rho * r;
                    ac[i] = mij - si + inv_rho * yc[i];
                }
                (ds, r2, nonzeros)
            })
            .collect();
        let (mut ds, mut r2, mut nonzeros) = (0.0, 0.0, 0usize);
        for (a, b, c) in sums {
            ds += a;
            r2 += b;
            nonzeros += c;
        }
        let step = Step {
            primal: r2.sqrt() / norm,
            dual: rho * ds.sqrt() / norm,
            rank,
            nonzeros,
            warm: svt.warm_calls > warm_before,
            seconds: t0.elapsed().as_secs_f64(),
        };
        out.log.push(step);
        if step.primal < p.tolerance && step.dual < p.tolerance {
            out.converged = true;
            break;
        }
    }
    out.sparse = MatRef::from_column_major_slice(&s, rows, cols).to_owned();
    Ok(out)
}
