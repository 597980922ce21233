//! The cubic spline SPH kernel (Monaghan 1992) with compact support `h`, normalised for
//! 2-D and 3-D, in the form of Koschier et al. 2019, "Smoothed Particle Hydrodynamics
//! Techniques for the Physics Based Simulation of Fluids and Solids", eq. (4):
//! with `q = |x| / h`,
//! `W(q) = k (6q^3 - 6q^2 + 1)` for `q <= 1/2`, `W(q) = 2k (1 - q)^3` for `1/2 < q <= 1`, else 0,
//! where `k = 8 / (pi h^3)` in 3-D and `k = 40 / (7 pi h^2)` in 2-D.

use std::f64::consts::PI;

/// The cubic spline kernel for support radius `h` in dimension 2 or 3.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CubicSpline {
    /// Support radius: `W(x) = 0` for `|x| >= h`.
    pub h: f64,
    /// Normalisation of `W`.
    k: f64,
    /// Normalisation of the derivative, `6k`.
    l: f64,
}

impl CubicSpline {
    /// The kernel with support radius `h` in `dim` dimensions (2 or 3; other values give 3).
    pub fn new(h: f64, dim: usize) -> CubicSpline {
        let k = if dim == 2 {
            40.0 / (7.0 * PI * h * h)
        } else {
            8.0 / (PI * h * h * h)
        };
        CubicSpline { h, k, l: 6.0 * k }
    }

    /// `W(r)` for distance `r`.
    #[inline]
    pub fn w(&self, r: f64) -> f64 {
        let q = r / self.h;
        if q <= 0.5 {
            self.k * (6.0 * q * q * q - 6.0 * q * q + 1.0)
        } else if q <= 1.0 {
            let f = 1.0 - q;
            2.0 * self.k * f * f * f
        } else {
            0.0
        }
    }

    /// `W(0)`, the particle's own contribution to its density.
    #[inline]
    pub fn w_zero(&self) -> f64 {
        self.k
    }

    /// `grad W(x)` for the offset `x = x_i - x_j` (zero at `x = 0` and outside the support).
    #[inline]
    pub fn grad(&self, x: [f64; 3]) -> [f64; 3] {
        let r2 = x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
        let r = r2.sqrt();
        let q = r / self.h;
        if r <= 1e-12 * self.h || q > 1.0 {
            return [0.0; 3];
        }
        // dW/dq = l q (3q - 2) on [0, 1/2], -l (1 - q)^2 on (1/2, 1]; dq/dx = x / (r h).
        let dwdq = if q <= 0.5 {
            self.l * q * (3.0 * q - 2.0)
        } else {
            -self.l * (1.0 - q) * (1.0 - q)
        };
        let s = dwdq / (r * self.h);
        [s * x[0], s * x[1], s * x[2]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Midpoint-rule integral of `W` over a grid covering the support.
    fn integral(dim: usize, h: f64, n: i32) -> f64 {
        let kern = CubicSpline::new(h, dim);
        let d = 2.0 * h / n as f64;
        let mut s = 0.0;
        let nz = if dim == 3 { n } else { 1 };
        for i in 0..n {
            for j in 0..n {
                for k in 0..nz {
                    let x = -h + (i as f64 + 0.5) * d;
                    let y = -h + (j as f64 + 0.5) * d;
                    let z = if dim == 3 {
                        -h + (k as f64 + 0.5) * d
                    } else {
                        0.0
                    };
                    s += kern.w((x * x + y * y + z * z).sqrt());
                }
            }
        }
        s * d.powi(dim as i32)
    }

    #[test]
    fn kernel_integrates_to_one() {
        assert!((integral(2, 0.1, 400) - 1.0).abs() < 1e-4);
        assert!((integral(3, 0.1, 120) - 1.0).abs() < 1e-3);
    }

    #[test]
    fn gradient_is_antisymmetric_and_matches_finite_differences() {
        for dim in [2, 3] {
            let kern = CubicSpline::new(0.2, dim);
            for x in [[0.03, -0.02, 0.01], [0.11, 0.05, -0.04], [0.0, 0.17, 0.0]] {
                let x = if dim == 2 { [x[0], x[1], 0.0] } else { x };
                let g = kern.grad(x);
                let gm = kern.grad([-x[0], -x[1], -x[2]]);
                let eps = 1e-6;
                for a in 0..dim {
                    assert!((g[a] + gm[a]).abs() < 1e-12);
                    let mut xp = x;
                    let mut xm = x;
                    xp[a] += eps;
                    xm[a] -= eps;
                    let r = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                    let fd = (kern.w(r(xp)) - kern.w(r(xm))) / (2.0 * eps);
                    assert!(
                        (fd - g[a]).abs() < 1e-5 * kern.w_zero() / 0.2,
                        "{fd} {}",
                        g[a]
                    );
                }
            }
            assert_eq!(kern.grad([0.3, 0.0, 0.0]), [0.0; 3]);
            assert_eq!(kern.w(0.2), 0.0);
        }
    }
}
