//! Radial basis function interpolation with an affine part (Arad et al. 1994, "Image warping
//! by radial basis functions"; the course's homework 1):
//!
//!   f(x) = sum_i a_i phi_i(|x - p_i|) + A x + b,
//!
//! with the coefficients a_i (2-vectors), A and b solving, for both coordinates at once, the
//! (n + 3) x (n + 3) system with two right-hand sides (the 2(n + 3) unknowns)
//!
//!   [ Phi  P ] [ a ]   [ q ]
//!   [ P^T  0 ] [ c ] = [ 0 ],   Phi_ij = phi_j(|p_i - p_j|),  P_i = [x_i, y_i, 1],
//!
//! whose last rows make the radial part orthogonal to affine maps, so an affine set of
//! control points is reproduced exactly. Solved once per fit by dense LU (nalgebra).

use super::{WarpError, WarpMap};
use cgnodes_api::node::Choice;
use nalgebra::DMatrix;

/// The radial function phi(d) with radius r.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// sqrt(d^2 + r^2) (Hardy).
    Multiquadric,
    /// 1 / sqrt(d^2 + r^2).
    InverseMultiquadric,
    /// exp(-d^2 / r^2).
    Gaussian,
    /// d^2 ln d (Duchon's thin-plate spline; the radius is unused).
    ThinPlate,
}

impl Choice for Kernel {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("thin_plate", Kernel::ThinPlate),
        ("multiquadric", Kernel::Multiquadric),
        ("inverse_multiquadric", Kernel::InverseMultiquadric),
        ("gaussian", Kernel::Gaussian),
    ];
}

impl Kernel {
    /// phi at squared distance `d2` for squared radius `r2`.
    #[inline(always)]
    pub fn phi(self, d2: f64, r2: f64) -> f64 {
        match self {
            Kernel::Multiquadric => (d2 + r2).sqrt(),
            Kernel::InverseMultiquadric => 1.0 / (d2 + r2).sqrt(),
            Kernel::Gaussian => (-d2 / r2).exp(),
            Kernel::ThinPlate => {
                if d2 > 0.0 {
                    0.5 * d2 * d2.ln()
                } else {
                    0.0
                }
            }
        }
    }
}

/// A fitted RBF map. Coordinates are taken relative to the centres' centroid, which keeps
/// the affine columns of the system on the scale of the distances.
#[derive(Clone, Debug)]
pub struct Rbf {
    centre: [f64; 2],
    p: Vec<[f64; 2]>,
    r2: Vec<f64>,
    a: Vec<[f64; 2]>,
    /// The affine part: f_k += m[k][0] x + m[k][1] y + m[k][2].
    m: [[f64; 3]; 2],
    kernel: Kernel,
}

impl Rbf {
    /// Solves for the map with f(p_i) = q_i. `radius` 0 gives each centre the distance to its
    /// nearest other centre (the course's suggestion); the points must already be checked
    /// (`super::check_points`): at least three, distinct, not on one line.
    pub fn fit(
        p: &[[f64; 2]],
        q: &[[f64; 2]],
        kernel: Kernel,
        radius: f64,
    ) -> Result<Rbf, WarpError> {
        let n = p.len();
        let c = p.iter().fold([0.0; 2], |s, x| {
            [s[0] + x[0] / n as f64, s[1] + x[1] / n as f64]
        });
        let pc: Vec<[f64; 2]> = p.iter().map(|x| [x[0] - c[0], x[1] - c[1]]).collect();
        let d2 = |i: usize, j: usize| (pc[i][0] - pc[j][0]).powi(2) + (pc[i][1] - pc[j][1]).powi(2);
        let r2: Vec<f64> = (0..n)
            .map(|j| {
                if radius > 0.0 {
                    radius * radius
                } else {
                    (0..n)
                        .filter(|&i| i != j)
                        .map(|i| d2(i, j))
                        .fold(f64::INFINITY, f64::min)
                }
            })
            .collect();
        let m = n + 3;
        let mut sys = DMatrix::<f64>::zeros(m, m);
        let mut rhs = DMatrix::<f64>::zeros(m, 2);
        for i in 0..n {
            for j in 0..n {
                sys[(i, j)] = kernel.phi(d2(i, j), r2[j]);
            }
            let row = [pc[i][0], pc[i][1], 1.0];
            for k in 0..3 {
                sys[(i, n + k)] = row[k];
                sys[(n + k, i)] = row[k];
            }
            rhs[(i, 0)] = q[i][0];
            rhs[(i, 1)] = q[i][1];
        }
        if sys.iter().any(|v| !v.is_finite()) {
            return Err(WarpError::Singular(
                "the kernel overflows at these distances; give a larger radius".into(),
            ));
        }
        let sol = sys.lu().solve(&rhs).ok_or_else(|| {
            WarpError::Singular("the RBF matrix has no inverse for these control points".into())
        })?;
        let a = (0..n).map(|i| [sol[(i, 0)], sol[(i, 1)]]).collect();
        let mut aff = [[0.0; 3]; 2];
        for (k, row) in aff.iter_mut().enumerate() {
            for (l, v) in row.iter_mut().enumerate() {
                *v = sol[(n + l, k)];
            }
        }
        let f = Rbf {
            centre: c,
            p: pc,
            r2,
            a,
            m: aff,
            kernel,
        };
        // An ill-conditioned system (nearly coincident centres, a gaussian of tiny radius)
        // solves to something that no longer interpolates: refuse it.
        let scale = q.iter().flatten().fold(1.0f64, |s, v| s.max(v.abs()));
        let res = super::residual(&f, p, q);
        if res.is_nan() || res > 1e-10 * scale.max(1000.0) {
            return Err(WarpError::Singular(format!(
                "the RBF system is too ill-conditioned: the solution misses a control point \
                 by {res:.3e} px"
            )));
        }
        Ok(f)
    }
}

impl WarpMap for Rbf {
    fn eval(&self, x: [f64; 2]) -> [f64; 2] {
        let x = [x[0] - self.centre[0], x[1] - self.centre[1]];
        let m = &self.m;
        let mut out = [
            m[0][0] * x[0] + m[0][1] * x[1] + m[0][2],
            m[1][0] * x[0] + m[1][1] * x[1] + m[1][2],
        ];
        for ((p, a), r2) in self.p.iter().zip(&self.a).zip(&self.r2) {
            let d2 = (x[0] - p[0]).powi(2) + (x[1] - p[1]).powi(2);
            let phi = self.kernel.phi(d2, *r2);
            out[0] += a[0] * phi;
            out[1] += a[1] * phi;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kernel_interpolates_and_reproduces_affine_sets() {
        let p = [
            [10.0, 10.0],
            [90.0, 15.0],
            [50.0, 70.0],
            [20.0, 95.0],
            [80.0, 80.0],
            [45.0, 30.0],
        ];
        let bent: Vec<[f64; 2]> = p
            .iter()
            .map(|x| [x[0] + 0.01 * x[1] * x[1], x[1] + 5.0])
            .collect();
        let affine: Vec<[f64; 2]> = p
            .iter()
            .map(|x| {
                [
                    0.9 * x[0] + 0.2 * x[1] + 3.0,
                    -0.1 * x[0] + 1.2 * x[1] - 4.0,
                ]
            })
            .collect();
        for (_, kernel) in Kernel::CHOICES {
            for radius in [0.0, 20.0] {
                let f = Rbf::fit(&p, &bent, *kernel, radius).unwrap();
                assert!(super::super::residual(&f, &p, &bent) < 1e-6, "{kernel:?}");
                let g = Rbf::fit(&p, &affine, *kernel, radius).unwrap();
                let y = g.eval([33.0, 61.0]);
                assert!(
                    (y[0] - (0.9 * 33.0 + 0.2 * 61.0 + 3.0)).abs() < 1e-9,
                    "{kernel:?}"
                );
                assert!(
                    (y[1] - (-0.1 * 33.0 + 1.2 * 61.0 - 4.0)).abs() < 1e-9,
                    "{kernel:?}"
                );
            }
        }
    }

    #[test]
    fn a_nearly_coincident_pair_with_a_tiny_gaussian_is_refused_or_interpolates() {
        let p = [[0.0, 0.0], [100.0, 0.0], [0.0, 100.0], [0.0, 1e-13]];
        let q = [[0.0, 0.0], [100.0, 0.0], [0.0, 100.0], [50.0, 50.0]];
        match Rbf::fit(&p, &q, Kernel::Multiquadric, 0.0) {
            Ok(f) => assert!(super::super::residual(&f, &p, &q) < 1e-6),
            Err(e) => assert!(matches!(e, WarpError::Singular(_))),
        }
    }
}
