//! `curve_interpolate`: a curve through a sequence of points at parameter values t (GAMES102
//! homework 2 / study book §3.3): the polynomial (barycentric form), cubic splines with four
//! end conditions, RBF, one Bézier curve on the points as control polygon, a C1 Bézier
//! spline, or a small network fitted to the points (`mlp`, an approximation). The algorithms are in the sibling files; this one checks input and samples.

use super::barycentric::Barycentric;
use super::bezier::{de_casteljau, BezierSpline};
use super::cubic_spline::{CubicSpline, EndCondition};
use super::curve_mlp::CurveMlp;
use super::curve_parameterize::{parameterize, Parameterization};
use super::rbf::{RbfCurve, RbfKernel};
use cgnodes_api::prelude::*;

/// The interpolation method (the `method` socket).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// The polynomial of degree n - 1, barycentric form.
    Polynomial,
    /// A C2 cubic spline.
    CubicSpline,
    /// Radial basis functions plus a linear part.
    Rbf,
    /// One Bézier curve with the points as control polygon (interpolates only the ends).
    Bezier,
    /// A C1 piecewise cubic Bézier curve through the points.
    BezierSpline,
    /// A small network t -> (x, y) trained on the points (approximates them).
    Mlp,
}

impl Choice for Method {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("cubic_spline", Method::CubicSpline),
        ("polynomial", Method::Polynomial),
        ("rbf", Method::Rbf),
        ("bezier", Method::Bezier),
        ("bezier_spline", Method::BezierSpline),
        ("mlp", Method::Mlp),
    ];
}

/// The cubic spline's end condition (the `end` socket).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SplineEnd {
    /// Zero second derivative.
    Natural,
    /// Given first derivatives (`start_tangent`, `end_tangent`).
    Clamped,
    /// Continuous third derivative at the second and second-to-last points.
    NotAKnot,
    /// A closed curve.
    Periodic,
}

impl Choice for SplineEnd {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("natural", SplineEnd::Natural),
        ("clamped", SplineEnd::Clamped),
        ("not_a_knot", SplineEnd::NotAKnot),
        ("periodic", SplineEnd::Periodic),
    ];
}

/// A method with its parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum Interpolation {
    /// See `Method::Polynomial`.
    Polynomial,
    /// See `Method::CubicSpline`.
    CubicSpline(EndCondition<2>),
    /// See `Method::Rbf`.
    Rbf(RbfKernel, f64),
    /// See `Method::Bezier`.
    Bezier,
    /// See `Method::BezierSpline`.
    BezierSpline,
    /// See `Method::Mlp`: hidden layer sizes, epochs, seed.
    Mlp(Vec<usize>, usize, u64),
}

/// A fitted curve: t -> (x, y) over [t_0, t_{n-1}] (for `Bezier`, [0, 1]).
pub struct Interpolant {
    f: Box<dyn Fn(f64) -> [f64; 2] + Send + Sync>,
    /// The parameter interval.
    pub domain: (f64, f64),
    /// For `mlp`: the training loss after every epoch (empty otherwise).
    pub losses: Vec<f64>,
}

impl Interpolant {
    /// The point at parameter `x`.
    pub fn eval(&self, x: f64) -> [f64; 2] {
        (self.f)(x)
    }

    /// `samples` points at evenly spaced parameters over the domain: (t, point).
    pub fn sample(&self, samples: usize) -> Vec<(f64, [f64; 2])> {
        let (a, b) = self.domain;
        (0..samples)
            .map(|k| {
                let x = if samples < 2 {
                    a
                } else if k + 1 == samples {
                    b
                } else {
                    a + (b - a) * k as f64 / (samples - 1) as f64
                };
                (x, self.eval(x))
            })
            .collect()
    }
}

/// Which input is at fault, and why.
pub type InterpError = (&'static str, String);

/// Fits `how` to points `p` at parameters `t` (strictly increasing, one per point). The
/// points must be finite; the caller checks that.
pub fn interpolate(
    p: &[[f64; 2]],
    t: &[f64],
    how: Interpolation,
) -> Result<Interpolant, InterpError> {
    let n = p.len();
    if t.len() != n {
        return Err(("t", format!("{} parameter values for {n} points", t.len())));
    }
    if n < 2 {
        return Err(("points", format!("needs at least 2 points, got {n}")));
    }
    if let Some(i) = t.iter().position(|x| !x.is_finite()) {
        return Err(("t", format!("t[{i}] is not finite")));
    }
    if let Some(i) = t
        .windows(2)
        .position(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
    {
        return Err((
            "t",
            format!("parameter values must increase: t[{}] <= t[{i}]", i + 1),
        ));
    }
    let domain = (t[0], t[n - 1]);
    let f: Box<dyn Fn(f64) -> [f64; 2] + Send + Sync> = match how {
        Interpolation::Polynomial => {
            let b = Barycentric::new(t, p);
            Box::new(move |x| b.eval(x))
        }
        Interpolation::CubicSpline(end) => {
            let s = CubicSpline::new(t, p, end).map_err(|e| ("points", e.to_string()))?;
            Box::new(move |x| s.eval(x))
        }
        Interpolation::Rbf(kernel, scale) => {
            if !(scale.is_finite() && scale > 0.0) {
                return Err(("scale", format!("must be a positive number, got {scale}")));
            }
            let r = RbfCurve::new(t, p, kernel, scale).map_err(|e| ("points", e.to_string()))?;
            Box::new(move |x| r.eval(x))
        }
        Interpolation::Bezier => {
            let c = p.to_vec();
            return Ok(Interpolant {
                f: Box::new(move |u| de_casteljau(&c, u)),
                domain: (0.0, 1.0),
                losses: Vec::new(),
            });
        }
        Interpolation::BezierSpline => {
            let s = BezierSpline::new(t, p);
            Box::new(move |x| s.eval(x))
        }
        Interpolation::Mlp(hidden, epochs, seed) => {
            let c = CurveMlp::fit(p, t, &hidden, epochs, seed);
            let losses = c.losses.clone();
            return Ok(Interpolant {
                f: Box::new(move |x| c.eval(x)),
                domain,
                losses,
            });
        }
    };
    Ok(Interpolant {
        f,
        domain,
        losses: Vec::new(),
    })
}

fn declare(b: &mut NodeBuilder) {
    b.doc("A curve through points: polynomial, cubic spline, RBF, Bézier or C1 Bézier spline.");
    b.add_input::<Vec<[f64; 2]>>("points")
        .doc("The points in order.");
    b.add_input::<Vec<f64>>("t").optional().doc(
        "Parameter values, one per point, increasing (default: chordal, from curve_parameterize).",
    );
    b.add_choice::<Method>("method")
        .doc("cubic_spline, polynomial (barycentric Lagrange), rbf, bezier (control polygon), bezier_spline (C1), mlp (a network t -> (x, y), approximates).");
    b.add_choice::<SplineEnd>("end")
        .doc("cubic_spline end condition; periodic closes the polygon (appends the first point when t is not given).");
    b.add_input::<[f64; 2]>("start_tangent")
        .default(Value::Vec2([0.0, 0.0]))
        .doc("clamped: dP/dt at the first point (scipy's clamped is zero).");
    b.add_input::<[f64; 2]>("end_tangent")
        .default(Value::Vec2([0.0, 0.0]))
        .doc("clamped: dP/dt at the last point.");
    b.add_choice::<RbfKernel>("kernel")
        .doc("rbf: gaussian, multiquadric, thin_plate.");
    b.add_input::<f64>("scale")
        .default(0.2)
        .range(1e-9, 1e9)
        .doc("rbf: phi(|t - t_j| / scale) (scipy's epsilon = 1 / scale), in units of t.");
    b.add_input::<Vec<i64>>("hidden")
        .default(Value::from(vec![32i64, 32]))
        .doc("mlp: hidden layer sizes (tanh).");
    b.add_input::<i64>("epochs")
        .default(3000)
        .range(1.0, 1e7)
        .doc("mlp: training steps (Adam, learning rate 0.01, all points per step).");
    b.add_input::<i64>("seed")
        .default(0)
        .min(0.0)
        .doc("mlp: the initialization's seed.");
    b.add_input::<i64>("samples")
        .default(200)
        .range(2.0, 1e7)
        .doc("Number of curve points, evenly spaced in t.");
    b.add_output::<Vec<[f64; 2]>>("curve");
    b.add_output::<Table>("table")
        .doc("Columns t, x, y of the samples; meta residual = max distance of the curve from the points it interpolates.");
}

/// The end condition of the cubic spline; `Clamped` reads and checks the two tangents.
fn end_condition(ctx: &ExecContext, end: SplineEnd) -> Result<EndCondition<2>, NodeError> {
    Ok(match end {
        SplineEnd::Natural => EndCondition::Natural,
        SplineEnd::Clamped => {
            let a: [f64; 2] = ctx.input("start_tangent")?;
            let b: [f64; 2] = ctx.input("end_tangent")?;
            for (s, v) in [("start_tangent", a), ("end_tangent", b)] {
                if !v.iter().all(|x| x.is_finite()) {
                    return Err(NodeError::invalid(s, "must be finite"));
                }
            }
            EndCondition::Clamped(a, b)
        }
        SplineEnd::NotAKnot => EndCondition::NotAKnot,
        SplineEnd::Periodic => EndCondition::Periodic,
    })
}

/// The MLP's hidden layer sizes (1 to 1024 each, at least one layer), epochs and seed.
fn mlp_settings(ctx: &ExecContext) -> Result<Interpolation, NodeError> {
    let hidden: Vec<i64> = ctx.input("hidden")?;
    let hidden = hidden
        .iter()
        .map(|&h| usize::try_from(h).ok().filter(|h| (1..=1024).contains(h)))
        .collect::<Option<Vec<usize>>>()
        .filter(|h| !h.is_empty())
        .ok_or_else(|| NodeError::invalid("hidden", "one to many sizes between 1 and 1024"))?;
    let epochs = usize::try_from(ctx.input::<i64>("epochs")?)
        .ok()
        .filter(|e| *e >= 1)
        .ok_or_else(|| NodeError::invalid("epochs", "must be at least 1"))?;
    let seed = u64::try_from(ctx.input::<i64>("seed")?)
        .map_err(|_| NodeError::invalid("seed", "must be >= 0"))?;
    Ok(Interpolation::Mlp(hidden, epochs, seed))
}

/// The interpolation `method` with its settings from the sockets.
fn interpolation(
    ctx: &ExecContext,
    method: Method,
    end: SplineEnd,
) -> Result<Interpolation, NodeError> {
    Ok(match method {
        Method::Polynomial => Interpolation::Polynomial,
        Method::CubicSpline => Interpolation::CubicSpline(end_condition(ctx, end)?),
        Method::Rbf => Interpolation::Rbf(ctx.choice("kernel")?, ctx.input("scale")?),
        Method::Bezier => Interpolation::Bezier,
        Method::BezierSpline => Interpolation::BezierSpline,
        Method::Mlp => mlp_settings(ctx)?,
    })
}

/// The interpolation residual: the largest distance between the curve and a point at its
/// parameter (only the two ends for a Bézier curve, which interpolates only those).
fn residual(f: &Interpolant, method: Method, p: &[[f64; 2]], t: &[f64]) -> f64 {
    let checked: Vec<(f64, [f64; 2])> = match method {
        Method::Bezier => vec![(0.0, p[0]), (1.0, p[p.len() - 1])],
        _ => t.iter().copied().zip(p.iter().copied()).collect(),
    };
    checked
        .iter()
        .map(|(x, q)| {
            let v = f.eval(*x);
            (v[0] - q[0]).hypot(v[1] - q[1])
        })
        .fold(0.0, f64::max)
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mut p: Vec<[f64; 2]> = ctx.input("points")?;
    let t: Option<Vec<f64>> = ctx.input_opt("t")?;
    let method: Method = ctx.choice("method")?;
    let end: SplineEnd = ctx.choice("end")?;
    let samples: i64 = ctx.input("samples")?;
    let samples = usize::try_from(samples)
        .ok()
        .filter(|s| *s >= 2)
        .ok_or_else(|| NodeError::invalid("samples", "must be at least 2"))?;
    if let Some(i) = p
        .iter()
        .position(|q| !(q[0].is_finite() && q[1].is_finite()))
    {
        return Err(NodeError::invalid(
            "points",
            format!("point {i} is not finite"),
        ));
    }
    let periodic = method == Method::CubicSpline && end == SplineEnd::Periodic;
    let t = match t {
        Some(t) => t,
        None => {
            if periodic && p.len() >= 2 && p[0] != p[p.len() - 1] {
                p.push(p[0]);
            }
            parameterize(&p, Parameterization::Chordal)
                .map_err(|e| NodeError::invalid("points", e.to_string()))?
        }
    };
    let how = interpolation(ctx, method, end)?;
    let f = interpolate(&p, &t, how).map_err(|(s, e)| NodeError::invalid(s, e))?;
    let residual = residual(&f, method, &p, &t);
    let s = f.sample(samples);
    let mut table = Table::with_columns(&["t", "x", "y"]);
    for (x, v) in &s {
        table.push_row(&[*x, v[0], v[1]]);
    }
    table
        .meta
        .insert("residual".into(), format!("{residual:e}"));
    if let (Some(a), Some(b)) = (f.losses.first(), f.losses.last()) {
        table
            .meta
            .insert("loss_first_epoch".into(), format!("{a:e}"));
        table
            .meta
            .insert("loss_last_epoch".into(), format!("{b:e}"));
    }
    ctx.set_output("curve", s.into_iter().map(|(_, v)| v).collect::<Vec<_>>());
    ctx.set_output("table", table);
    Ok(())
}

/// Registers `curve_interpolate`.
pub fn register(r: &mut Registry) {
    r.add("curve_interpolate", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dozen points of a wavy open curve, with uneven spacing.
    fn points() -> Vec<[f64; 2]> {
        (0..12)
            .map(|i| {
                let x = i as f64 + 0.3 * (i as f64 * 1.7).sin();
                [x, (0.8 * x).sin() * 2.0 + 0.1 * x]
            })
            .collect()
    }

    #[test]
    fn every_method_passes_through_its_points() {
        let p = points();
        let t = parameterize(&p, Parameterization::Chordal).unwrap();
        let mut closed = p.clone();
        closed.push(p[0]);
        let tc = parameterize(&closed, Parameterization::Centripetal).unwrap();
        let cases = [
            (Interpolation::Polynomial, &p, &t),
            (Interpolation::CubicSpline(EndCondition::Natural), &p, &t),
            (
                Interpolation::CubicSpline(EndCondition::Clamped([1.0, 0.0], [0.0, -1.0])),
                &p,
                &t,
            ),
            (Interpolation::CubicSpline(EndCondition::NotAKnot), &p, &t),
            (
                Interpolation::CubicSpline(EndCondition::Periodic),
                &closed,
                &tc,
            ),
            (Interpolation::Rbf(RbfKernel::Gaussian, 0.1), &p, &t),
            (Interpolation::Rbf(RbfKernel::Multiquadric, 0.1), &p, &t),
            (Interpolation::Rbf(RbfKernel::ThinPlate, 1.0), &p, &t),
            (Interpolation::BezierSpline, &p, &t),
        ];
        for (how, p, t) in cases {
            let f = interpolate(p, t, how.clone()).unwrap();
            for (x, q) in t.iter().zip(p.iter()) {
                let v = f.eval(*x);
                let e = (v[0] - q[0]).abs().max((v[1] - q[1]).abs());
                assert!(e < 1e-10, "{how:?}: {e:e}");
            }
        }
        // A Bézier curve interpolates its end points only.
        let f = interpolate(&p, &t, Interpolation::Bezier).unwrap();
        assert_eq!(f.eval(0.0), p[0]);
        assert_eq!(f.eval(1.0), p[11]);
        let s = f.sample(5);
        assert_eq!(s[4].1, p[11]);
    }

    #[test]
    fn bad_input_names_the_socket() {
        let p = points();
        let t = parameterize(&p, Parameterization::Chordal).unwrap();
        let e = interpolate(&p, &t[..5], Interpolation::Polynomial)
            .err()
            .unwrap();
        assert_eq!(e.0, "t");
        let mut t2 = t.clone();
        t2[3] = t2[2];
        let e = interpolate(&p, &t2, Interpolation::BezierSpline)
            .err()
            .unwrap();
        assert!(e.0 == "t" && e.1.contains("t[3] <= t[2]"), "{e:?}");
        let e = interpolate(&p[..1], &t[..1], Interpolation::Polynomial)
            .err()
            .unwrap();
        assert_eq!(e.0, "points");
        let e = interpolate(&p, &t, Interpolation::Rbf(RbfKernel::Gaussian, -1.0))
            .err()
            .unwrap();
        assert_eq!(e.0, "scale");
        let e = interpolate(&p, &t, Interpolation::CubicSpline(EndCondition::Periodic))
            .err()
            .unwrap();
        assert!(e.1.contains("closed"), "{e:?}");
    }
}
