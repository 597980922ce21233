//! `curve_parameterize`: parameter values t_0 = 0 < t_1 < ... < t_{n-1} = 1 for a sequence of
//! points, by the four rules of GAMES102's study book, §3.3.2.1 (Floater & Surazhsky 2006,
//! "Parameterization for curve interpolation", reviews them). With d_i = |P_{i+1} - P_i|:
//!
//! - uniform:     t_{i+1} - t_i = 1;
//! - chordal:     t_{i+1} - t_i = d_i;
//! - centripetal: t_{i+1} - t_i = sqrt(d_i)  (Lee 1989);
//! - Foley-Nielson (Foley & Nielson 1989):
//!   t_{i+1} - t_i = d_i (1 + 3/2 th_i d_{i-1} / (d_{i-1} + d_i) + 3/2 th_{i+1} d_{i+1} / (d_i + d_{i+1})),
//!   th_i = min(pi - alpha_i, pi/2), alpha_i the angle at P_i between P_{i-1} and P_{i+1}
//!   (a straight run has alpha = pi, th = 0: chordal); the terms of the missing neighbours of
//!   the end segments are left out.
//!
//! then divided by their sum.

use cgnodes_api::prelude::*;

/// The rule that spaces the parameter values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parameterization {
    /// Equal steps.
    Uniform,
    /// Steps proportional to the chord lengths.
    Chordal,
    /// Steps proportional to the square roots of the chord lengths.
    Centripetal,
    /// Chord lengths enlarged where the polygon turns (Foley & Nielson 1989).
    FoleyNielson,
}

impl Choice for Parameterization {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("chordal", Parameterization::Chordal),
        ("uniform", Parameterization::Uniform),
        ("centripetal", Parameterization::Centripetal),
        ("foley_nielsen", Parameterization::FoleyNielson),
    ];
}

/// Why a sequence of points cannot be parameterized.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamError {
    /// Fewer than two points.
    TooFew(usize),
    /// A coordinate is NaN or infinite.
    NotFinite(usize),
    /// Points `i` and `i + 1` coincide (a zero chord).
    Repeated(usize),
}

impl std::fmt::Display for ParamError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ParamError::TooFew(n) => write!(f, "needs at least 2 points, got {n}"),
            ParamError::NotFinite(i) => write!(f, "point {i} is not finite"),
            ParamError::Repeated(i) => write!(
                f,
                "points {i} and {} are the same point (a zero-length chord); remove one",
                i + 1
            ),
        }
    }
}

/// Checks that there are at least two finite points and no two consecutive ones coincide.
pub fn check_points(p: &[[f64; 2]]) -> Result<(), ParamError> {
    if p.len() < 2 {
        return Err(ParamError::TooFew(p.len()));
    }
    if let Some(i) = p
        .iter()
        .position(|q| !(q[0].is_finite() && q[1].is_finite()))
    {
        return Err(ParamError::NotFinite(i));
    }
    if let Some(i) = p.windows(2).position(|w| w[0] == w[1]) {
        return Err(ParamError::Repeated(i));
    }
    Ok(())
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (b[0] - a[0]).hypot(b[1] - a[1])
}

/// The angle at `b` between `a` and `c`, in [0, pi].
fn angle(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    let u = [a[0] - b[0], a[1] - b[1]];
    let v = [c[0] - b[0], c[1] - b[1]];
    (u[0] * v[1] - u[1] * v[0])
        .abs()
        .atan2(u[0] * v[0] + u[1] * v[1])
}

/// Parameter values of `p` by `method`, normalized to [0, 1] (t_0 = 0, t_{n-1} = 1 exactly).
pub fn parameterize(p: &[[f64; 2]], method: Parameterization) -> Result<Vec<f64>, ParamError> {
    check_points(p)?;
    let n = p.len();
    let d: Vec<f64> = p.windows(2).map(|w| dist(w[0], w[1])).collect();
    let steps: Vec<f64> = match method {
        Parameterization::Uniform => vec![1.0; n - 1],
        Parameterization::Chordal => d.clone(),
        Parameterization::Centripetal => d.iter().map(|x| x.sqrt()).collect(),
        Parameterization::FoleyNielson => {
            // theta[i] at interior point i (0 at the ends).
            let theta: Vec<f64> = (0..n)
                .map(|i| {
                    if i == 0 || i == n - 1 {
                        0.0
                    } else {
                        let a = angle(p[i - 1], p[i], p[i + 1]);
                        (std::f64::consts::PI - a).min(std::f64::consts::FRAC_PI_2)
                    }
                })
                .collect();
            (0..n - 1)
                .map(|i| {
                    let mut f = 1.0;
                    if i > 0 {
                        f += 1.5 * theta[i] * d[i - 1] / (d[i - 1] + d[i]);
                    }
                    if i + 1 < n - 1 {
                        f += 1.5 * theta[i + 1] * d[i + 1] / (d[i] + d[i + 1]);
                    }
                    d[i] * f
                })
                .collect()
        }
    };
    let total: f64 = steps.iter().sum();
    let mut t = Vec::with_capacity(n);
    let mut acc = 0.0;
    t.push(0.0);
    for s in &steps[..n - 2] {
        acc += s;
        t.push(acc / total);
    }
    t.push(1.0);
    Ok(t)
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Parameter values in [0, 1] for a sequence of points: uniform, chordal, centripetal, Foley-Nielson.");
    b.add_input::<Vec<[f64; 2]>>("points")
        .doc("The points in order; consecutive points must differ.");
    b.add_choice::<Parameterization>("method")
        .doc("chordal, uniform, centripetal or foley_nielsen (GAMES102 study book 3.3.2.1).");
    b.add_output::<Vec<f64>>("t")
        .doc("One value per point, increasing from 0 to 1.");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let p: Vec<[f64; 2]> = ctx.input("points")?;
    let method: Parameterization = ctx.choice("method")?;
    let t = parameterize(&p, method).map_err(|e| NodeError::invalid("points", e.to_string()))?;
    ctx.set_output("t", t);
    Ok(())
}

/// Registers `curve_parameterize`.
pub fn register(r: &mut Registry) {
    r.add("curve_parameterize", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Three sides of a 3 x 4 rectangle: chords 3, 4, 3 with right angles at P1 and P2.
    const P: [[f64; 2]; 4] = [[0.0, 0.0], [3.0, 0.0], [3.0, 4.0], [0.0, 4.0]];

    fn close(a: &[f64], b: &[f64]) {
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() < 1e-15, "{a:?} vs {b:?}");
        }
    }

    #[test]
    fn four_points_by_hand() {
        let t = |m| parameterize(&P, m).unwrap();
        close(
            &t(Parameterization::Uniform),
            &[0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0],
        );
        close(&t(Parameterization::Chordal), &[0.0, 0.3, 0.7, 1.0]);
        let s3 = 3f64.sqrt();
        let sum = 2.0 * s3 + 2.0;
        close(
            &t(Parameterization::Centripetal),
            &[0.0, s3 / sum, (s3 + 2.0) / sum, 1.0],
        );
        // Right angles: theta = min(pi - pi/2, pi/2) = pi/2 at P1 and P2.
        // Delta_0 = 3 (1 + 3/2 (pi/2) 4/7), Delta_1 = 4 (1 + 2 * 3/2 (pi/2) 3/7), Delta_2 = Delta_0.
        let d0 = 3.0 * (1.0 + 1.5 * (PI / 2.0) * 4.0 / 7.0);
        let d1 = 4.0 * (1.0 + 2.0 * 1.5 * (PI / 2.0) * 3.0 / 7.0);
        let sum = 2.0 * d0 + d1;
        close(
            &t(Parameterization::FoleyNielson),
            &[0.0, d0 / sum, (d0 + d1) / sum, 1.0],
        );
    }

    #[test]
    fn straight_runs_make_foley_nielson_chordal() {
        let p = [[0.0, 0.0], [1.0, 1.0], [3.0, 3.0], [3.5, 3.5]];
        close(
            &parameterize(&p, Parameterization::FoleyNielson).unwrap(),
            &parameterize(&p, Parameterization::Chordal).unwrap(),
        );
    }

    #[test]
    fn bad_points_are_named() {
        let p = [[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [2.0, 0.0]];
        let e = parameterize(&p, Parameterization::Uniform).unwrap_err();
        assert_eq!(e, ParamError::Repeated(1));
        assert!(e.to_string().contains("points 1 and 2"));
        assert_eq!(
            parameterize(&[[0.0, 0.0]], Parameterization::Chordal),
            Err(ParamError::TooFew(1))
        );
        assert_eq!(
            parameterize(&[[0.0, 0.0], [f64::NAN, 1.0]], Parameterization::Chordal),
            Err(ParamError::NotFinite(1))
        );
    }
}
