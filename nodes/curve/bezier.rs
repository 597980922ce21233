//! Bézier curves (Farin, "Curves and Surfaces for CAGD", ch. 3-4, 7):
//!
//! - `de_casteljau`: the point at u in [0, 1] of the Bézier curve of a control polygon, by
//!   repeated linear interpolation (Farin eq. 3.5), stable for any degree;
//! - `BezierSpline`: a piecewise cubic through the points, piece i over [t_i, t_{i+1}] with
//!   control points P_i, P_i + h_i m_i / 3, P_{i+1} - h_i m_{i+1} / 3, P_{i+1}, so the curve
//!   is C1 in t (Hermite to Bézier, Farin §7.2). The tangents m_i are Bessel's (Farin §9.3,
//!   the parabola's derivative through P_{i-1}, P_i, P_{i+1} at t_i):
//!   m_i = (h_i d_{i-1} + h_{i-1} d_i) / (h_{i-1} + h_i), d_i = (P_{i+1} - P_i) / h_i, and at
//!   the ends the end parabola's: m_0 = ((2 h_0 + h_1) d_0 - h_0 d_1) / (h_0 + h_1).

/// The point at `u` of the Bézier curve with control points `ctrl` (at least one).
pub fn de_casteljau(ctrl: &[[f64; 2]], u: f64) -> [f64; 2] {
    let mut b = ctrl.to_vec();
    for r in 1..ctrl.len() {
        for i in 0..ctrl.len() - r {
            let next = b[i + 1];
            for (v, w) in b[i].iter_mut().zip(next) {
                *v = (1.0 - u) * *v + u * w;
            }
        }
    }
    b[0]
}

/// A C1 piecewise cubic Bézier curve through points at increasing parameters.
#[derive(Clone, Debug)]
pub struct BezierSpline {
    t: Vec<f64>,
    /// Four control points per piece.
    pieces: Vec<[[f64; 2]; 4]>,
}

impl BezierSpline {
    /// The spline through `p` at the strictly increasing `t` (at least two, same length).
    pub fn new(t: &[f64], p: &[[f64; 2]]) -> BezierSpline {
        let n = p.len();
        let h: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        let d: Vec<[f64; 2]> = (0..n - 1)
            .map(|i| std::array::from_fn(|k| (p[i + 1][k] - p[i][k]) / h[i]))
            .collect();
        let m: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                std::array::from_fn(|k| {
                    if n == 2 {
                        d[0][k]
                    } else if i == 0 {
                        ((2.0 * h[0] + h[1]) * d[0][k] - h[0] * d[1][k]) / (h[0] + h[1])
                    } else if i == n - 1 {
                        let (a, b) = (h[n - 3], h[n - 2]);
                        ((2.0 * b + a) * d[n - 2][k] - b * d[n - 3][k]) / (a + b)
                    } else {
                        (h[i] * d[i - 1][k] + h[i - 1] * d[i][k]) / (h[i - 1] + h[i])
                    }
                })
            })
            .collect();
        let pieces = (0..n - 1)
            .map(|i| {
                let c = h[i] / 3.0;
                [
                    p[i],
                    [p[i][0] + c * m[i][0], p[i][1] + c * m[i][1]],
                    [p[i + 1][0] - c * m[i + 1][0], p[i + 1][1] - c * m[i + 1][1]],
                    p[i + 1],
                ]
            })
            .collect();
        BezierSpline {
            t: t.to_vec(),
            pieces,
        }
    }

    /// The control points of every piece.
    pub fn pieces(&self) -> &[[[f64; 2]; 4]] {
        &self.pieces
    }

    /// The point at parameter `x` (clamped to [t_0, t_{n-1}]).
    pub fn eval(&self, x: f64) -> [f64; 2] {
        let n = self.t.len();
        let i = self.t.partition_point(|&k| k <= x).clamp(1, n - 1) - 1;
        let u = ((x - self.t[i]) / (self.t[i + 1] - self.t[i])).clamp(0.0, 1.0);
        de_casteljau(&self.pieces[i], u)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn de_casteljau_matches_bernstein_form() {
        let c = [[0.0, 0.0], [1.0, 2.0], [3.0, 3.0], [4.0, 0.0]];
        let u: f64 = 0.3;
        let v = 1.0 - u;
        let b = [v * v * v, 3.0 * u * v * v, 3.0 * u * u * v, u * u * u];
        let want: [f64; 2] = std::array::from_fn(|k| (0..4).map(|i| b[i] * c[i][k]).sum::<f64>());
        let got = de_casteljau(&c, u);
        assert!((got[0] - want[0]).abs() < 1e-15 && (got[1] - want[1]).abs() < 1e-15);
        assert_eq!(de_casteljau(&c, 0.0), c[0]);
        assert_eq!(de_casteljau(&c, 1.0), c[3]);
    }

    #[test]
    fn spline_interpolates_with_c1_joins() {
        let t = [0.0, 0.3, 0.5, 1.0];
        let p = [[0.0, 0.0], [1.0, 1.0], [2.0, 0.5], [3.0, 2.0]];
        let s = BezierSpline::new(&t, &p);
        for (x, q) in t.iter().zip(&p) {
            assert_eq!(s.eval(*x), *q);
        }
        // C1 in t: the derivative 3 (b3 - b2) / h_i at the end of piece i equals
        // 3 (b1' - b0') / h_{i+1} at the start of piece i + 1.
        for i in 0..2 {
            let (a, b) = (s.pieces()[i], s.pieces()[i + 1]);
            for k in 0..2 {
                let l = 3.0 * (a[3][k] - a[2][k]) / (t[i + 1] - t[i]);
                let r = 3.0 * (b[1][k] - b[0][k]) / (t[i + 2] - t[i + 1]);
                assert!((l - r).abs() < 1e-12, "{l} {r}");
            }
        }
    }
}
