//! Linear least squares for the fitting nodes: min |A c - y|^2 (+ lambda |c|^2), solved by
//! faer's Householder QR of the column-equilibrated matrix (Golub & Van Loan, "Matrix
//! Computations", §5.3; the same scaling as numpy's `polyfit`), never by the normal
//! equations, whose condition number is the square of A's. Ridge regression solves the
//! stacked problem [A; sqrt(lambda) I] c = [y; 0] (Björck, "Numerical Methods for Least
//! Squares Problems", §2.7), which is the same minimizer.

use faer::linalg::solvers::SolveLstsq;
use faer::Mat;

/// A solved least-squares problem.
#[derive(Clone, Debug)]
pub struct LstsqSolution {
    /// The coefficients c.
    pub c: Vec<f64>,
    /// The 2-norm condition number of the (column-scaled, stacked for ridge) matrix that
    /// was factored: largest over smallest singular value.
    pub condition: f64,
}

/// Why a least-squares problem has no usable solution.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LstsqError {
    /// A column of A is zero (or not finite) at every row.
    #[error("basis function {0} is zero (or not finite) at every x")]
    ZeroColumn(usize),
    /// Fewer rows than unknowns (without ridge).
    #[error("{unknowns} coefficients from {values} values: too few values")]
    TooFewValues {
        /// Number of coefficients.
        unknowns: usize,
        /// Number of values.
        values: usize,
    },
    /// faer's SVD failed (its error, as `Debug`).
    #[error("SVD failed: {0}")]
    Svd(String),
    /// The matrix is rank deficient.
    #[error("the least-squares matrix is singular (rank deficient)")]
    Singular,
    /// The solution has a NaN or infinite entry.
    #[error("the least-squares solution is not finite")]
    NotFinite,
}

/// Solves min |A c - y|^2 + lambda |c|^2 for the m x n matrix `a` (m >= n without ridge).
/// Errors when a column is zero or the solution is not finite (a singular problem).
pub fn lstsq(a: &Mat<f64>, y: &[f64], lambda: f64) -> Result<LstsqSolution, LstsqError> {
    let (m, n) = (a.nrows(), a.ncols());
    let scale: Vec<f64> = (0..n)
        .map(|j| (0..m).map(|i| a[(i, j)] * a[(i, j)]).sum::<f64>().sqrt())
        .collect();
    if let Some(j) = scale.iter().position(|s| !(*s > 0.0 && s.is_finite())) {
        return Err(LstsqError::ZeroColumn(j));
    }
    let rows = if lambda > 0.0 { m + n } else { m };
    if rows < n {
        return Err(LstsqError::TooFewValues {
            unknowns: n,
            values: m,
        });
    }
    let mut s = Mat::<f64>::zeros(rows, n);
    let mut rhs = Mat::<f64>::zeros(rows, 1);
    for j in 0..n {
        for i in 0..m {
            s[(i, j)] = a[(i, j)] / scale[j];
        }
        if lambda > 0.0 {
            // lambda |c|^2 = lambda |D^-1 (D c)|^2: the stacked rows sqrt(lambda) / d_j.
            s[(m + j, j)] = lambda.sqrt() / scale[j];
        }
    }
    for (i, v) in y.iter().enumerate() {
        rhs[(i, 0)] = *v;
    }
    let sv = s
        .singular_values()
        .map_err(|e| LstsqError::Svd(format!("{e:?}")))?;
    let condition = match (sv.first(), sv.last()) {
        (Some(&hi), Some(&lo)) if lo > 0.0 => hi / lo,
        _ => f64::INFINITY,
    };
    if !condition.is_finite() {
        return Err(LstsqError::Singular);
    }
    let x = s.qr().solve_lstsq(&rhs);
    let c: Vec<f64> = (0..n).map(|j| x[(j, 0)] / scale[j]).collect();
    if c.iter().any(|v| !v.is_finite()) {
        return Err(LstsqError::NotFinite);
    }
    Ok(LstsqSolution { c, condition })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overdetermined_line_and_ridge_shrinkage() {
        // y = 1 + 2x + noise that is orthogonal to [1, x]: the exact line comes back.
        let x = [0.0, 1.0, 2.0, 3.0];
        let noise = [1.0, -1.0, -1.0, 1.0];
        let a = Mat::from_fn(4, 2, |i, j| if j == 0 { 1.0 } else { x[i] });
        let y: Vec<f64> = (0..4).map(|i| 1.0 + 2.0 * x[i] + 0.1 * noise[i]).collect();
        let s = lstsq(&a, &y, 0.0).unwrap();
        assert!((s.c[0] - 1.0).abs() < 1e-14 && (s.c[1] - 2.0).abs() < 1e-14);
        // Ridge: (A^T A + lambda I) c = A^T y, checked against the 2 x 2 normal equations.
        let lambda = 0.5;
        let r = lstsq(&a, &y, lambda).unwrap();
        let (s0, s1, s2) = (4.0, 6.0, 14.0);
        let (b0, b1) = (
            y.iter().sum::<f64>(),
            y.iter().zip(&x).map(|(a, b)| a * b).sum::<f64>(),
        );
        let (m00, m01, m11) = (s0 + lambda, s1, s2 + lambda);
        let det = m00 * m11 - m01 * m01;
        let want = [(m11 * b0 - m01 * b1) / det, (m00 * b1 - m01 * b0) / det];
        assert!((r.c[0] - want[0]).abs() < 1e-13 && (r.c[1] - want[1]).abs() < 1e-13);
        let zero = Mat::<f64>::zeros(3, 1);
        assert!(lstsq(&zero, &[1.0, 2.0, 3.0], 0.0).is_err());
    }
}
