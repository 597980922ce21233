//! The Runge phenomenon and the stability of barycentric interpolation (issue 26), run with
//! `cargo bench --bench curves`.
//!
//! For f(x) = 1 / (1 + 25 x^2) on [-1, 1] and n = 3..=60 nodes, the largest error over 2001
//! evenly spaced points of:
//! - the interpolating polynomial at n equispaced nodes (barycentric form): Runge's divergence;
//! - the not-a-knot cubic spline at the same nodes: O(h^4) convergence;
//! - the polynomial at n Chebyshev points of the second kind, barycentric form: geometric
//!   convergence down to rounding (Berrut & Trefethen 2004, §6);
//! - the same polynomial from monomial coefficients, the Vandermonde system solved by faer's
//!   LU with partial pivoting and evaluated by Horner: exact in exact arithmetic, but the
//!   system's condition number grows exponentially and the error follows it.
//!
//! Writes `docs/curves_runge.svg` and `docs/curves_runge.csv` and prints the table.

use cgnodes::chart::{draw, Chart, Series};
use cgnodes::nodes::curve::barycentric::Barycentric;
use cgnodes::nodes::curve::cubic_spline::{CubicSpline, EndCondition};
use faer::linalg::solvers::Solve;
use faer::Mat;
use std::path::Path;

fn runge(x: f64) -> f64 {
    1.0 / (1.0 + 25.0 * x * x)
}

fn max_error(f: impl Fn(f64) -> f64) -> f64 {
    (0..=2000)
        .map(|k| {
            let x = -1.0 + 2.0 * k as f64 / 2000.0;
            (f(x) - runge(x)).abs()
        })
        .fold(0.0, f64::max)
}

/// Monomial coefficients from the Vandermonde system, then Horner.
fn vandermonde(x: &[f64]) -> impl Fn(f64) -> f64 {
    let n = x.len();
    let a = Mat::<f64>::from_fn(n, n, |i, j| x[i].powi(j as i32));
    let b = Mat::<f64>::from_fn(n, 1, |i, _| runge(x[i]));
    let c = a.partial_piv_lu().solve(&b);
    let c: Vec<f64> = (0..n).map(|i| c[(i, 0)]).collect();
    move |t| c.iter().rev().fold(0.0, |acc, k| acc * t + k)
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let names = [
        "polynomial, equispaced",
        "cubic spline (not-a-knot), equispaced",
        "polynomial, Chebyshev points (barycentric)",
        "polynomial, Chebyshev points (Vandermonde solve)",
    ];
    let mut series: Vec<Series> = names
        .iter()
        .map(|n| Series {
            label: n.to_string(),
            points: Vec::new(),
        })
        .collect();
    let mut csv = vec![vec![
        "n".to_string(),
        "equispaced_polynomial".into(),
        "equispaced_spline".into(),
        "chebyshev_barycentric".into(),
        "chebyshev_vandermonde".into(),
    ]];
    println!("n  max error: equispaced polynomial | spline | Chebyshev barycentric | Chebyshev Vandermonde");
    for n in 3..=60usize {
        let eq: Vec<f64> = (0..n)
            .map(|i| -1.0 + 2.0 * i as f64 / (n - 1) as f64)
            .collect();
        let ch: Vec<f64> = (0..n)
            .map(|i| -(std::f64::consts::PI * i as f64 / (n - 1) as f64).cos())
            .collect();
        let val = |x: &[f64]| x.iter().map(|&v| [runge(v)]).collect::<Vec<[f64; 1]>>();
        let p_eq = Barycentric::new(&eq, &val(&eq));
        let s_eq = CubicSpline::new(&eq, &val(&eq), EndCondition::NotAKnot).expect("spline");
        let p_ch = Barycentric::new(&ch, &val(&ch));
        let v_ch = vandermonde(&ch);
        let e = [
            max_error(|x| p_eq.eval(x)[0]),
            max_error(|x| s_eq.eval(x)[0]),
            max_error(|x| p_ch.eval(x)[0]),
            max_error(&v_ch),
        ];
        println!(
            "{n:2}  {:9.3e} | {:9.3e} | {:9.3e} | {:9.3e}",
            e[0], e[1], e[2], e[3]
        );
        for (s, v) in series.iter_mut().zip(e) {
            s.points.push((n as f64, v.max(1e-17)));
        }
        csv.push(
            std::iter::once(n.to_string())
                .chain(e.iter().map(|v| format!("{v:e}")))
                .collect(),
        );
    }
    let chart = Chart {
        title: "Runge's function 1/(1+25x^2): max error against the number of nodes".into(),
        x_label: "nodes n".into(),
        y_label: "max |p(x) - f(x)| on [-1, 1]".into(),
        series,
        failures: Vec::new(),
        log_x: false,
        log_y: true,
    };
    let svg = root.join("docs/curves_runge.svg");
    draw(&chart, &svg).expect("chart");
    std::fs::write(
        root.join("docs/curves_runge.csv"),
        cgnodes::io::csv::to_text(csv),
    )
    .expect("csv");
    eprintln!("wrote {} and docs/curves_runge.csv", svg.display());
}
