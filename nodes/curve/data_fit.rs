//! `data_fit`: a function y = f(x) fitted to points (GAMES102 homework 1 / study book §4.1):
//!
//! - `polynomial`: least squares over 1, x, ..., x^degree;
//! - `ridge`: the same plus lambda |c|^2 (every coefficient penalized, the constant too:
//!   scikit-learn's `Ridge(fit_intercept=False)` on those columns);
//! - `gaussian_basis`: least squares over 1 and `basis_count` Gaussians
//!   exp(-(x - mu_k)^2 / (2 sigma^2)), mu_k evenly spaced over [min x, max x];
//! - `interpolate`: the polynomial of degree n - 1 through all points (the curve by the
//!   barycentric form, `barycentric.rs`; the monomial coefficients by QR, as accurate as
//!   the Vandermonde condition number allows, which the table reports).
//!
//! Solved by QR (`lstsq.rs`), not the normal equations.

use super::barycentric::Barycentric;
use super::lstsq::lstsq;
use cgnodes_api::prelude::*;
use faer::Mat;

/// The model (the `model` socket).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelKind {
    /// Least-squares polynomial.
    Polynomial,
    /// Ridge-regularized polynomial.
    Ridge,
    /// Constant plus Gaussians.
    GaussianBasis,
    /// Interpolating polynomial.
    Interpolate,
}

impl Choice for ModelKind {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("polynomial", ModelKind::Polynomial),
        ("ridge", ModelKind::Ridge),
        ("gaussian_basis", ModelKind::GaussianBasis),
        ("interpolate", ModelKind::Interpolate),
    ];
}

/// A model with its parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Model {
    /// Polynomial of this degree.
    Polynomial(usize),
    /// Polynomial of this degree with this lambda.
    Ridge(usize, f64),
    /// `count` Gaussians of width `sigma` (0: the spacing of their centres).
    GaussianBasis { count: usize, sigma: f64 },
    /// Degree n - 1 through every point.
    Interpolate,
}

/// A fitted function.
#[derive(Clone, Debug)]
pub struct Fit {
    /// Monomial coefficients c_0..c_d (increasing powers), or the constant then the Gaussians'.
    pub coefficients: Vec<f64>,
    /// Gaussian centres (empty for polynomials).
    pub centres: Vec<f64>,
    /// Gaussian width.
    pub sigma: f64,
    /// The condition number of the factored matrix (`lstsq`).
    pub condition: f64,
    /// RMS of f(x_i) - y_i.
    pub rms: f64,
    interp: Option<Barycentric<1>>,
}

impl Fit {
    /// f(x).
    pub fn eval(&self, x: f64) -> f64 {
        if let Some(b) = &self.interp {
            return b.eval(x)[0];
        }
        if self.centres.is_empty() {
            return self
                .coefficients
                .iter()
                .rev()
                .fold(0.0, |acc, c| acc * x + c);
        }
        let s2 = 2.0 * self.sigma * self.sigma;
        self.coefficients[0]
            + self.coefficients[1..]
                .iter()
                .zip(&self.centres)
                .map(|(c, m)| c * (-(x - m) * (x - m) / s2).exp())
                .sum::<f64>()
    }
}

/// Which socket is at fault, and why.
pub type FitError = (&'static str, String);

fn distinct_count(x: &[f64]) -> usize {
    let mut s = x.to_vec();
    s.sort_by(f64::total_cmp);
    s.dedup();
    s.len()
}

/// The least-squares problem of a model: the design matrix (one column per basis function),
/// the Gaussians' centres and width (none for polynomials) and the ridge lambda.
struct Design {
    a: Mat<f64>,
    centres: Vec<f64>,
    sigma: f64,
    lambda: f64,
}

/// The Vandermonde matrix of 1, x, ..., x^d at `x`.
fn monomials(x: &[f64], d: usize) -> Mat<f64> {
    Mat::from_fn(x.len(), d + 1, |i, j| x[i].powi(j as i32))
}

/// The design of a (ridge) polynomial of degree `d`: `lambda` must be >= 0, and without it
/// the points need `d + 1` distinct x values.
fn polynomial_design(
    x: &[f64],
    d: usize,
    lambda: f64,
    distinct: usize,
) -> Result<Design, FitError> {
    if !(lambda.is_finite() && lambda >= 0.0) {
        return Err(("lambda", format!("must be >= 0, got {lambda}")));
    }
    if lambda == 0.0 && distinct <= d {
        return Err((
            "degree",
            format!(
                "degree {d} needs at least {} distinct x values, got {distinct}",
                d + 1
            ),
        ));
    }
    Ok(Design {
        a: monomials(x, d),
        centres: Vec::new(),
        sigma: 0.0,
        lambda,
    })
}

/// The design of a constant plus `count` Gaussians centred evenly over [min x, max x], of
/// width `sigma` (0: the spacing of the centres, or the x range for one Gaussian).
fn gaussian_design(
    x: &[f64],
    count: usize,
    sigma: f64,
    distinct: usize,
) -> Result<Design, FitError> {
    if count == 0 {
        return Err(("basis_count", "must be at least 1".into()));
    }
    if distinct <= count {
        return Err((
            "basis_count",
            format!("{count} Gaussians and a constant need at least {} distinct x values, got {distinct}", count + 1),
        ));
    }
    let (lo, hi) = x
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let centres: Vec<f64> = (0..count)
        .map(|k| {
            if count == 1 {
                0.5 * (lo + hi)
            } else {
                lo + (hi - lo) * k as f64 / (count - 1) as f64
            }
        })
        .collect();
    let sigma = if sigma > 0.0 {
        sigma
    } else if count > 1 {
        (hi - lo) / (count - 1) as f64
    } else {
        hi - lo
    };
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(("sigma", format!("must be a positive number, got {sigma}")));
    }
    let s2 = 2.0 * sigma * sigma;
    let a = Mat::from_fn(x.len(), count + 1, |i, j| {
        if j == 0 {
            1.0
        } else {
            let d = x[i] - centres[j - 1];
            (-d * d / s2).exp()
        }
    });
    Ok(Design {
        a,
        centres,
        sigma,
        lambda: 0.0,
    })
}

/// Fits `model` to the points (x_i, y_i) (finite, at least one).
pub fn fit(points: &[[f64; 2]], model: Model) -> Result<Fit, FitError> {
    let n = points.len();
    if n == 0 {
        return Err(("points", "no points".into()));
    }
    if let Some(i) = points
        .iter()
        .position(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return Err(("points", format!("point {i} is not finite")));
    }
    let x: Vec<f64> = points.iter().map(|p| p[0]).collect();
    let y: Vec<f64> = points.iter().map(|p| p[1]).collect();
    let distinct = distinct_count(&x);
    let design = match model {
        Model::Polynomial(d) => polynomial_design(&x, d, 0.0, distinct)?,
        Model::Ridge(d, lambda) => polynomial_design(&x, d, lambda, distinct)?,
        Model::Interpolate => {
            if distinct < n {
                return Err(("points", "interpolation needs distinct x values".into()));
            }
            polynomial_design(&x, n - 1, 0.0, distinct)?
        }
        Model::GaussianBasis { count, sigma } => gaussian_design(&x, count, sigma, distinct)?,
    };
    let socket = match model {
        Model::GaussianBasis { .. } => "sigma",
        Model::Interpolate => "points",
        _ => "degree",
    };
    let sol = lstsq(&design.a, &y, design.lambda).map_err(|e| (socket, e.to_string()))?;
    let interp = matches!(model, Model::Interpolate).then(|| {
        let f: Vec<[f64; 1]> = y.iter().map(|v| [*v]).collect();
        Barycentric::new(&x, &f)
    });
    let mut f = Fit {
        coefficients: sol.c,
        centres: design.centres,
        sigma: design.sigma,
        condition: sol.condition,
        rms: 0.0,
        interp,
    };
    f.rms = (points
        .iter()
        .map(|p| (f.eval(p[0]) - p[1]).powi(2))
        .sum::<f64>()
        / n as f64)
        .sqrt();
    Ok(f)
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Fits y = f(x) to points: least-squares polynomial, ridge, Gaussian basis, or interpolating polynomial.");
    b.add_input::<Vec<[f64; 2]>>("points")
        .doc("The data (x, y).");
    b.add_choice::<ModelKind>("model")
        .doc("polynomial, ridge, gaussian_basis or interpolate (degree n - 1).");
    b.add_input::<i64>("degree")
        .default(3)
        .range(0.0, 200.0)
        .doc("polynomial and ridge: the degree.");
    b.add_input::<f64>("lambda")
        .default(1e-3)
        .min(0.0)
        .doc("ridge: the weight of |c|^2.");
    b.add_input::<i64>("basis_count")
        .default(8)
        .range(1.0, 10000.0)
        .doc("gaussian_basis: number of Gaussians, centred evenly over the x range.");
    b.add_input::<f64>("sigma")
        .default(0.0)
        .min(0.0)
        .doc("gaussian_basis: the Gaussians' width; 0 = the spacing of their centres.");
    b.add_input::<i64>("samples")
        .default(200)
        .range(2.0, 1e7)
        .doc("Number of curve points, evenly spaced over the x range.");
    b.add_output::<Vec<[f64; 2]>>("curve");
    b.add_output::<Vec<f64>>("coefficients")
        .doc("Polynomials: c_0..c_d in increasing powers; gaussian_basis: the constant, then one per Gaussian.");
    b.add_output::<Table>("table")
        .doc("rms_residual, condition (of the column-scaled matrix QR factored), normal_condition (its square: that of the normal matrix).");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let p: Vec<[f64; 2]> = ctx.input("points")?;
    let kind: ModelKind = ctx.choice("model")?;
    let count = |name: &str, v: i64| {
        usize::try_from(v).map_err(|_| NodeError::invalid(name, "must be >= 0"))
    };
    let degree = count("degree", ctx.input("degree")?)?;
    let model = match kind {
        ModelKind::Polynomial => Model::Polynomial(degree),
        ModelKind::Ridge => Model::Ridge(degree, ctx.input("lambda")?),
        ModelKind::GaussianBasis => Model::GaussianBasis {
            count: count("basis_count", ctx.input("basis_count")?)?,
            sigma: ctx.input("sigma")?,
        },
        ModelKind::Interpolate => Model::Interpolate,
    };
    let samples = count("samples", ctx.input("samples")?)?.max(2);
    let f = fit(&p, model).map_err(|(s, e)| NodeError::invalid(s, e))?;
    if f.condition > 1e12 {
        ctx.log(format!(
            "warning: the fit's matrix has condition number {:.2e}: its coefficients keep about {} digits",
            f.condition,
            (16.0 - f.condition.log10()).max(0.0).round()
        ));
    }
    let (lo, hi) = p
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), q| {
            (a.min(q[0]), b.max(q[0]))
        });
    let curve: Vec<[f64; 2]> = (0..samples)
        .map(|k| {
            let x = if k + 1 == samples {
                hi
            } else {
                lo + (hi - lo) * k as f64 / (samples - 1) as f64
            };
            [x, f.eval(x)]
        })
        .collect();
    ctx.set_output("curve", curve);
    ctx.set_output("coefficients", f.coefficients.clone());
    ctx.set_output(
        "table",
        Table::from_row(&[
            ("rms_residual", f.rms),
            ("condition", f.condition),
            ("normal_condition", f.condition * f.condition),
        ]),
    );
    Ok(())
}

/// Registers `data_fit`.
pub fn register(r: &mut Registry) {
    r.add("data_fit", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(g: impl Fn(f64) -> f64, n: usize) -> Vec<[f64; 2]> {
        (0..n)
            .map(|i| {
                let x = -1.0 + 2.0 * i as f64 / (n - 1) as f64 + 0.01 * (i as f64).sin();
                [x, g(x)]
            })
            .collect()
    }

    #[test]
    fn a_polynomial_of_the_same_degree_is_fitted_exactly() {
        let c = [0.5, -1.0, 2.0, 0.25, -3.0];
        let g = |x: f64| c.iter().rev().fold(0.0, |a, k| a * x + k);
        let f = fit(&sample(g, 30), Model::Polynomial(4)).unwrap();
        for (a, b) in f.coefficients.iter().zip(c) {
            assert!((a - b).abs() < 1e-12, "{:?}", f.coefficients);
        }
        assert!(f.rms < 1e-13);
        // Interpolation of 5 points of the quartic: the same polynomial.
        let f = fit(&sample(g, 5), Model::Interpolate).unwrap();
        for (a, b) in f.coefficients.iter().zip(c) {
            assert!((a - b).abs() < 1e-11, "{:?}", f.coefficients);
        }
        assert!((f.eval(0.3) - g(0.3)).abs() < 1e-13);
    }

    #[test]
    fn gaussian_basis_and_ridge_behave() {
        let pts = sample(|x| (3.0 * x).sin(), 40);
        let f = fit(
            &pts,
            Model::GaussianBasis {
                count: 10,
                sigma: 0.0,
            },
        )
        .unwrap();
        // numpy's lstsq on the same basis gives rms 0.0071003016153070.
        assert!((f.rms - 0.0071003016153070).abs() < 1e-12, "{}", f.rms);
        assert_eq!(f.coefficients.len(), 11);
        // The least-squares residual is orthogonal to every basis function.
        let s2 = 2.0 * f.sigma * f.sigma;
        for k in 0..=10 {
            let dot: f64 = pts
                .iter()
                .map(|p| {
                    let b = if k == 0 {
                        1.0
                    } else {
                        (-(p[0] - f.centres[k - 1]).powi(2) / s2).exp()
                    };
                    b * (f.eval(p[0]) - p[1])
                })
                .sum();
            assert!(dot.abs() < 1e-12, "{k}: {dot}");
        }
        // Ridge shrinks: a larger lambda, a smaller coefficient norm.
        let norm = |l| {
            let f = fit(&pts, Model::Ridge(6, l)).unwrap();
            f.coefficients.iter().map(|c| c * c).sum::<f64>()
        };
        assert!(norm(1.0) < norm(1e-3));
    }

    #[test]
    fn bad_input_names_the_socket() {
        let pts = [[0.0, 1.0], [1.0, 2.0], [1.0, 3.0]];
        assert_eq!(fit(&pts, Model::Polynomial(2)).unwrap_err().0, "degree");
        assert_eq!(fit(&pts, Model::Interpolate).unwrap_err().0, "points");
        assert_eq!(
            fit(&[[0.0, 1.0], [f64::NAN, 2.0]], Model::Polynomial(1))
                .unwrap_err()
                .0,
            "points"
        );
        assert_eq!(fit(&pts, Model::Ridge(1, -1.0)).unwrap_err().0, "lambda");
        assert_eq!(
            fit(
                &pts,
                Model::GaussianBasis {
                    count: 3,
                    sigma: 0.0
                }
            )
            .unwrap_err()
            .0,
            "basis_count"
        );
    }
}
