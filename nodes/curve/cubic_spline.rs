//! Interpolating cubic splines (de Boor, "A Practical Guide to Splines", ch. IV; the same
//! formulation as scipy's `CubicSpline`): on [t_i, t_{i+1}], with h_i = t_{i+1} - t_i and
//! divided differences d_i = (f_{i+1} - f_i) / h_i, the cubic Hermite piece of the slopes s_i
//! and s_{i+1}. C2 continuity at the interior knots gives
//!
//!   h_i s_{i-1} + 2 (h_{i-1} + h_i) s_i + h_{i-1} s_{i+1} = 3 (h_i d_{i-1} + h_{i-1} d_i),
//!
//! and the end condition the first and last rows:
//! - natural: f'' = 0 at both ends: 2 s_0 + s_1 = 3 d_0, s_{n-2} + 2 s_{n-1} = 3 d_{n-2};
//! - clamped: s_0 and s_{n-1} given (scipy's `clamped` is zero slopes);
//! - not-a-knot: f''' continuous at t_1 and t_{n-2} (three points: the parabola through them);
//! - periodic: f_0 = f_{n-1}, s_0 = s_{n-1} and f'' equal at both ends, the rows wrapping
//!   around (a cyclic system).
//!
//! The (n x n, tridiagonal up to two corner entries) system is solved by faer's sparse LU,
//! all coordinates at once as right-hand-side columns.

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;
use std::collections::BTreeMap;

/// The end condition of a cubic spline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EndCondition<const D: usize> {
    /// Zero second derivative at both ends.
    Natural,
    /// Given first derivatives at the start and the end.
    Clamped([f64; D], [f64; D]),
    /// Continuous third derivative at the second and the second-to-last knots.
    NotAKnot,
    /// A closed curve: the first and last values must be equal.
    Periodic,
}

/// Why a spline cannot be built.
#[derive(Clone, Debug, PartialEq)]
pub enum SplineError {
    /// Fewer knots than the end condition needs.
    TooFew { got: usize, need: usize },
    /// The knots do not increase strictly at index `i` (t_{i+1} <= t_i).
    NotIncreasing(usize),
    /// A periodic spline whose last value differs from its first.
    NotClosed,
    /// The lengths of t and f differ.
    Lengths(usize, usize),
    /// The linear solve failed (reported by faer) or produced non-finite slopes.
    Solve(String),
}

impl std::fmt::Display for SplineError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SplineError::TooFew { got, need } => {
                write!(f, "needs at least {need} points, got {got}")
            }
            SplineError::NotIncreasing(i) => {
                write!(f, "parameter values must increase: t[{}] <= t[{i}]", i + 1)
            }
            SplineError::NotClosed => write!(
                f,
                "a periodic spline needs the last point equal to the first (a closed polygon)"
            ),
            SplineError::Lengths(a, b) => write!(f, "{a} parameter values for {b} points"),
            SplineError::Solve(e) => write!(f, "the spline system could not be solved: {e}"),
        }
    }
}

/// A piecewise cubic in Hermite form: knots, values and slopes.
#[derive(Clone, Debug)]
pub struct CubicSpline<const D: usize> {
    t: Vec<f64>,
    f: Vec<[f64; D]>,
    s: Vec<[f64; D]>,
}

/// Checks lengths, count and strictly increasing knots.
pub fn check_knots(t: &[f64], n: usize, need: usize) -> Result<(), SplineError> {
    if t.len() != n {
        return Err(SplineError::Lengths(t.len(), n));
    }
    if n < need {
        return Err(SplineError::TooFew { got: n, need });
    }
    match t
        .windows(2)
        .position(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
    {
        Some(i) => Err(SplineError::NotIncreasing(i)),
        None => Ok(()),
    }
}

impl<const D: usize> CubicSpline<D> {
    /// The spline through (t_i, f_i) with end condition `end`.
    pub fn new(t: &[f64], f: &[[f64; D]], end: EndCondition<D>) -> Result<Self, SplineError> {
        let n = f.len();
        let need = match end {
            EndCondition::Periodic => 3,
            _ => 2,
        };
        check_knots(t, n, need)?;
        if matches!(end, EndCondition::Periodic) && f[0] != f[n - 1] {
            return Err(SplineError::NotClosed);
        }
        let h: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        let d: Vec<[f64; D]> = (0..n - 1)
            .map(|i| std::array::from_fn(|k| (f[i + 1][k] - f[i][k]) / h[i]))
            .collect();
        let s = if n == 2 && !matches!(end, EndCondition::Clamped(..)) {
            vec![d[0]; 2]
        } else if n == 3 && matches!(end, EndCondition::NotAKnot) {
            // The parabola p(t) = f_0 + d_0 (t - t_0) + c (t - t_0)(t - t_1).
            let c: [f64; D] = std::array::from_fn(|k| (d[1][k] - d[0][k]) / (h[0] + h[1]));
            [-h[0], h[0], h[0] + 2.0 * h[1]]
                .iter()
                .map(|&a| std::array::from_fn(|k| d[0][k] + c[k] * a))
                .collect()
        } else {
            solve_slopes(&h, &d, end)?
        };
        Ok(CubicSpline {
            t: t.to_vec(),
            f: f.to_vec(),
            s,
        })
    }

    /// The index of the piece holding `x` (the end pieces extend outside the knots).
    fn piece(&self, x: f64) -> usize {
        let n = self.t.len();
        self.t.partition_point(|&k| k <= x).clamp(1, n - 1) - 1
    }

    /// The polynomial coefficients (c0, c1, c2, c3) of piece `i` in powers of t - t_i.
    fn coefficients(&self, i: usize) -> [[f64; D]; 4] {
        let h = self.t[i + 1] - self.t[i];
        let (f0, f1, s0, s1) = (self.f[i], self.f[i + 1], self.s[i], self.s[i + 1]);
        let mut c = [[0.0; D]; 4];
        for k in 0..D {
            let d = (f1[k] - f0[k]) / h;
            c[0][k] = f0[k];
            c[1][k] = s0[k];
            c[2][k] = (3.0 * d - 2.0 * s0[k] - s1[k]) / h;
            c[3][k] = (s0[k] + s1[k] - 2.0 * d) / (h * h);
        }
        c
    }

    /// The value (`order` 0) or the first or second derivative at `x`.
    pub fn derivative(&self, x: f64, order: u8) -> [f64; D] {
        let n = self.t.len();
        if order == 0 && x == self.t[n - 1] {
            // The last knot ends a piece (u = h): its value exactly, not rounded through the cubic.
            return self.f[n - 1];
        }
        let i = self.piece(x);
        let u = x - self.t[i];
        let c = self.coefficients(i);
        std::array::from_fn(|k| match order {
            0 => c[0][k] + u * (c[1][k] + u * (c[2][k] + u * c[3][k])),
            1 => c[1][k] + u * (2.0 * c[2][k] + 3.0 * u * c[3][k]),
            _ => 2.0 * c[2][k] + 6.0 * u * c[3][k],
        })
    }

    /// The value at `x`.
    pub fn eval(&self, x: f64) -> [f64; D] {
        self.derivative(x, 0)
    }
}

/// Assembles and solves the slope system (n >= 3, or n >= 4 for not-a-knot, n >= 2 clamped).
fn solve_slopes<const D: usize>(
    h: &[f64],
    d: &[[f64; D]],
    end: EndCondition<D>,
) -> Result<Vec<[f64; D]>, SplineError> {
    let n = h.len() + 1;
    // Entries are summed per (row, column): a 3-point periodic system has prev == next.
    let mut a: BTreeMap<(usize, usize), f64> = BTreeMap::new();
    let mut add = |i: usize, j: usize, v: f64| *a.entry((i, j)).or_insert(0.0) += v;
    let m = if matches!(end, EndCondition::Periodic) {
        n - 1
    } else {
        n
    };
    let mut rhs = Mat::<f64>::zeros(m, D);
    let interior = |i: usize, prev: usize, rhs: &mut Mat<f64>| {
        let (hp, hi) = (h[prev], h[i]);
        for k in 0..D {
            rhs[(i, k)] = 3.0 * (hi * d[prev][k] + hp * d[i][k]);
        }
        [(prev, hi), (i, 2.0 * (hp + hi)), ((i + 1) % m, hp)]
    };
    if matches!(end, EndCondition::Periodic) {
        for i in 0..m {
            for (j, v) in interior(i, (i + m - 1) % m, &mut rhs) {
                add(i, j, v);
            }
        }
    } else {
        for i in 1..n - 1 {
            for (j, v) in interior(i, i - 1, &mut rhs) {
                add(i, j, v);
            }
        }
        let l = n - 1;
        match end {
            EndCondition::Natural => {
                add(0, 0, 2.0);
                add(0, 1, 1.0);
                add(l, l - 1, 1.0);
                add(l, l, 2.0);
                for k in 0..D {
                    rhs[(0, k)] = 3.0 * d[0][k];
                    rhs[(l, k)] = 3.0 * d[l - 1][k];
                }
            }
            EndCondition::Clamped(a0, a1) => {
                add(0, 0, 1.0);
                add(l, l, 1.0);
                for k in 0..D {
                    rhs[(0, k)] = a0[k];
                    rhs[(l, k)] = a1[k];
                }
            }
            EndCondition::NotAKnot => {
                let (h0, h1) = (h[0], h[1]);
                let (ha, hb) = (h[l - 2], h[l - 1]);
                add(0, 0, h1);
                add(0, 1, h0 + h1);
                add(l, l - 1, ha + hb);
                add(l, l, ha);
                for k in 0..D {
                    rhs[(0, k)] =
                        ((h0 + 2.0 * (h0 + h1)) * h1 * d[0][k] + h0 * h0 * d[1][k]) / (h0 + h1);
                    rhs[(l, k)] = (hb * hb * d[l - 2][k]
                        + (2.0 * (ha + hb) + hb) * ha * d[l - 1][k])
                        / (ha + hb);
                }
            }
            EndCondition::Periodic => unreachable!("handled above"),
        }
    }
    let trips: Vec<Triplet<usize, usize, f64>> = a
        .into_iter()
        .map(|((i, j), v)| Triplet::new(i, j, v))
        .collect();
    let mat = SparseColMat::<usize, f64>::try_new_from_triplets(m, m, &trips)
        .map_err(|e| SplineError::Solve(format!("{e:?}")))?;
    let lu = mat
        .sp_lu()
        .map_err(|e| SplineError::Solve(format!("{e:?}")))?;
    let x = lu.solve(&rhs);
    let mut s: Vec<[f64; D]> = (0..m).map(|i| std::array::from_fn(|k| x[(i, k)])).collect();
    if matches!(end, EndCondition::Periodic) {
        s.push(s[0]);
    }
    if s.iter().flatten().any(|v| !v.is_finite()) {
        return Err(SplineError::Solve("non-finite slopes".into()));
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: [f64; 6] = [0.0, 0.15, 0.4, 0.5, 0.8, 1.0];

    fn values(g: impl Fn(f64) -> f64) -> Vec<[f64; 1]> {
        T.iter().map(|&x| [g(x)]).collect()
    }

    #[test]
    fn every_end_condition_interpolates() {
        let mut f = values(|x| (3.0 * x).sin());
        for end in [
            EndCondition::Natural,
            EndCondition::Clamped([1.0], [-2.0]),
            EndCondition::NotAKnot,
        ] {
            let s = CubicSpline::new(&T, &f, end).unwrap();
            for (x, y) in T.iter().zip(&f) {
                assert!((s.eval(*x)[0] - y[0]).abs() < 1e-14, "{end:?}");
            }
        }
        f[5] = f[0];
        let s = CubicSpline::new(&T, &f, EndCondition::Periodic).unwrap();
        for (x, y) in T.iter().zip(&f) {
            assert!((s.eval(*x)[0] - y[0]).abs() < 1e-14);
        }
        for order in 1..=2 {
            let (a, b) = (s.derivative(0.0, order)[0], s.derivative(1.0, order)[0]);
            assert!((a - b).abs() < 1e-12, "order {order}: {a} vs {b}");
        }
    }

    #[test]
    fn natural_ends_are_straight_and_clamped_slopes_are_kept() {
        let f = values(|x| x.exp());
        let s = CubicSpline::new(&T, &f, EndCondition::Natural).unwrap();
        assert!(s.derivative(0.0, 2)[0].abs() < 1e-12);
        assert!(s.derivative(1.0, 2)[0].abs() < 1e-12);
        let s = CubicSpline::new(&T, &f, EndCondition::Clamped([0.5], [3.0])).unwrap();
        assert!((s.derivative(0.0, 1)[0] - 0.5).abs() < 1e-14);
        assert!((s.derivative(1.0, 1)[0] - 3.0).abs() < 1e-14);
    }

    #[test]
    fn not_a_knot_reproduces_cubics_and_continuity_holds() {
        let g = |x: f64| 4.0 * x * x * x - 2.0 * x * x + x - 1.0;
        let s = CubicSpline::new(&T, &values(g), EndCondition::NotAKnot).unwrap();
        for k in 0..=50 {
            let x = k as f64 / 50.0;
            assert!((s.eval(x)[0] - g(x)).abs() < 1e-13, "{x}");
        }
        // C2 at interior knots of a natural spline of other data.
        let s = CubicSpline::new(&T, &values(|x| (5.0 * x).cos()), EndCondition::Natural).unwrap();
        for &k in &T[1..5] {
            let e = 1e-9;
            let (l, r) = (s.derivative(k - e, 2)[0], s.derivative(k + e, 2)[0]);
            assert!((l - r).abs() < 1e-6, "{l} {r}");
        }
    }

    #[test]
    fn bad_knots_are_refused() {
        let f = values(|x| x);
        assert_eq!(
            CubicSpline::new(&[0.0, 0.2, 0.2, 0.5, 0.8, 1.0], &f, EndCondition::Natural)
                .unwrap_err(),
            SplineError::NotIncreasing(1)
        );
        assert_eq!(
            CubicSpline::new(&T, &f, EndCondition::Periodic).unwrap_err(),
            SplineError::NotClosed
        );
        assert!(matches!(
            CubicSpline::<1>::new(&[0.0], &[[1.0]], EndCondition::Natural),
            Err(SplineError::TooFew { got: 1, need: 2 })
        ));
    }
}
