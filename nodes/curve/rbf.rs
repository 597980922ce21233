//! Radial basis function interpolation over the parameter line (GAMES102 study book §3.3;
//! Fasshauer, "Meshfree Approximation Methods with MATLAB", ch. 6 and 8): with r = |t - t_j|
//! / scale,
//!
//!   f(t) = sum_j a_j phi(|t - t_j| / scale) + b_0 + b_1 t,
//!   [ Phi  P ] [ a ]   [ f ]
//!   [ P^T  0 ] [ b ] = [ 0 ],   Phi_ij = phi(|t_i - t_j| / scale),  P_i = [1, t_i],
//!
//! the linear part and the side conditions P^T a = 0 making the system well posed for the
//! conditionally positive definite kernels (multiquadric of order 1, thin plate of order 2)
//! and reproducing straight lines. This is scipy's `RBFInterpolator` with `degree=1` and
//! `epsilon = 1 / scale` (its multiquadric is -sqrt(1 + r^2), which only flips the sign of
//! the a_j). The system is solved by faer's dense LU with partial pivoting.

use cgnodes_api::node::Choice;
use faer::linalg::solvers::Solve;
use faer::Mat;

/// The radial function phi(r).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RbfKernel {
    /// exp(-r^2).
    Gaussian,
    /// sqrt(1 + r^2) (Hardy).
    Multiquadric,
    /// r^2 ln r (Duchon's thin-plate spline; `scale` does not change the interpolant).
    ThinPlate,
}

impl Choice for RbfKernel {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("gaussian", RbfKernel::Gaussian),
        ("multiquadric", RbfKernel::Multiquadric),
        ("thin_plate", RbfKernel::ThinPlate),
    ];
}

impl RbfKernel {
    /// phi(r), r >= 0.
    pub fn phi(self, r: f64) -> f64 {
        match self {
            RbfKernel::Gaussian => (-r * r).exp(),
            RbfKernel::Multiquadric => (1.0 + r * r).sqrt(),
            RbfKernel::ThinPlate => {
                if r > 0.0 {
                    r * r * r.ln()
                } else {
                    0.0
                }
            }
        }
    }
}

/// Why an RBF interpolant cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RbfError {
    /// Fewer than two nodes, or not one value per node.
    #[error("needs at least 2 nodes and one value each, got {0}")]
    TooFewNodes(usize),
    /// The kernel scale is not a positive number.
    #[error("scale must be a positive number, got {0}")]
    Scale(f64),
    /// The interpolation system cannot be solved.
    #[error("the RBF system is singular for these nodes and this scale")]
    Singular,
}

/// An RBF interpolant with values in R^D.
#[derive(Clone, Debug)]
pub struct RbfCurve<const D: usize> {
    t: Vec<f64>,
    a: Vec<[f64; D]>,
    b: [[f64; D]; 2],
    kernel: RbfKernel,
    scale: f64,
}

impl<const D: usize> RbfCurve<D> {
    /// Solves for the interpolant of `f` at the distinct nodes `t` (at least two).
    pub fn new(t: &[f64], f: &[[f64; D]], kernel: RbfKernel, scale: f64) -> Result<Self, RbfError> {
        let n = t.len();
        if n < 2 || f.len() != n {
            return Err(RbfError::TooFewNodes(n));
        }
        if !(scale.is_finite() && scale > 0.0) {
            return Err(RbfError::Scale(scale));
        }
        let m = n + 2;
        let mut a = Mat::<f64>::zeros(m, m);
        let mut rhs = Mat::<f64>::zeros(m, D);
        for i in 0..n {
            for j in 0..n {
                a[(i, j)] = kernel.phi((t[i] - t[j]).abs() / scale);
            }
            a[(i, n)] = 1.0;
            a[(n, i)] = 1.0;
            a[(i, n + 1)] = t[i];
            a[(n + 1, i)] = t[i];
            for k in 0..D {
                rhs[(i, k)] = f[i][k];
            }
        }
        let x = a.partial_piv_lu().solve(&rhs);
        if (0..m).any(|i| (0..D).any(|k| !x[(i, k)].is_finite())) {
            return Err(RbfError::Singular);
        }
        Ok(RbfCurve {
            t: t.to_vec(),
            a: (0..n).map(|i| std::array::from_fn(|k| x[(i, k)])).collect(),
            b: [
                std::array::from_fn(|k| x[(n, k)]),
                std::array::from_fn(|k| x[(n + 1, k)]),
            ],
            kernel,
            scale,
        })
    }

    /// f(x).
    pub fn eval(&self, x: f64) -> [f64; D] {
        let mut v: [f64; D] = std::array::from_fn(|k| self.b[0][k] + self.b[1][k] * x);
        for (tj, aj) in self.t.iter().zip(&self.a) {
            let p = self.kernel.phi((x - tj).abs() / self.scale);
            for k in 0..D {
                v[k] += aj[k] * p;
            }
        }
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_and_reproduces_lines() {
        let t: [f64; 5] = [0.0, 0.2, 0.35, 0.6, 1.0];
        let f: Vec<[f64; 2]> = t.iter().map(|&x| [x.sin(), 2.0 * x - 1.0]).collect();
        for kernel in [
            RbfKernel::Gaussian,
            RbfKernel::Multiquadric,
            RbfKernel::ThinPlate,
        ] {
            let r = RbfCurve::new(&t, &f, kernel, 0.3).unwrap();
            for (x, y) in t.iter().zip(&f) {
                let v = r.eval(*x);
                assert!((v[0] - y[0]).abs() < 1e-12 && (v[1] - y[1]).abs() < 1e-12);
            }
            // The second coordinate is a line: reproduced everywhere.
            assert!((r.eval(0.77)[1] - 0.54).abs() < 1e-12, "{kernel:?}");
        }
        assert!(RbfCurve::new(&t, &f, RbfKernel::Gaussian, 0.0).is_err());
    }
}
