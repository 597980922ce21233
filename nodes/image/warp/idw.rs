//! Inverse distance weighting with locally fitted linear maps (Shepard 1968; Ruprecht and
//! Müller 1995, "A framework for scattered data interpolation"; the form of the USTC CG 2024
//! homework 1):
//!
//!   f(x) = sum_i w_i(x) f_i(x),  f_i(x) = q_i + D_i (x - p_i),
//!   w_i(x) = sigma_i(x) / sum_j sigma_j(x),  sigma_i(x) = 1 / |x - p_i|^mu,
//!
//! with each 2x2 D_i the weighted least-squares fit over the other control points,
//! D_i = argmin sum_{j != i} sigma_i(p_j) |q_i + D_i (p_j - p_i) - q_j|^2. As x -> p_i the
//! weight w_i -> 1, so f(p_i) = q_i (returned exactly at p_i).

use super::WarpMap;

/// A fitted IDW map.
#[derive(Clone, Debug)]
pub struct Idw {
    p: Vec<[f64; 2]>,
    q: Vec<[f64; 2]>,
    /// D_i, row-major [[a, b], [c, d]].
    d: Vec<[[f64; 2]; 2]>,
    mu: f64,
}

/// Shepard weights sigma_i = 1 / d2_i^(mu/2), scaled by the nearest point's so that the
/// largest is 1 (no overflow near a control point; the scale cancels). `None` when `x`
/// coincides with a point: then the index of that point.
fn weights(p: &[[f64; 2]], x: [f64; 2], mu: f64, out: &mut Vec<f64>) -> Option<usize> {
    out.clear();
    let mut dmin = f64::INFINITY;
    for (i, pi) in p.iter().enumerate() {
        let d2 = (x[0] - pi[0]).powi(2) + (x[1] - pi[1]).powi(2);
        if d2 == 0.0 {
            return Some(i);
        }
        dmin = dmin.min(d2);
        out.push(d2);
    }
    let e = 0.5 * mu;
    for d2 in out.iter_mut() {
        *d2 = if e == 1.0 {
            dmin / *d2
        } else {
            (dmin / *d2).powf(e)
        };
    }
    None
}

impl Idw {
    /// Fits the local maps D_i. Where the other points do not determine D_i (one point, or
    /// all on a line through p_i) the fit is regularized towards the identity.
    pub fn fit(p: &[[f64; 2]], q: &[[f64; 2]], mu: f64) -> Idw {
        let n = p.len();
        let mut d = Vec::with_capacity(n);
        let mut w = Vec::new();
        for i in 0..n {
            // Weights of the other points as seen from p_i (p_i itself is skipped).
            let others: Vec<[f64; 2]> = (0..n).filter(|&j| j != i).map(|j| p[j]).collect();
            let js: Vec<usize> = (0..n).filter(|&j| j != i).collect();
            // Normal equations: D M = C with M = sum s dp dp^T, C = sum s dq dp^T.
            let mut m = [[0.0; 2]; 2];
            let mut c = [[0.0; 2]; 2];
            if weights(&others, p[i], mu, &mut w).is_none() {
                for (k, &j) in js.iter().enumerate() {
                    let dp = [p[j][0] - p[i][0], p[j][1] - p[i][1]];
                    let dq = [q[j][0] - q[i][0], q[j][1] - q[i][1]];
                    for r in 0..2 {
                        for s in 0..2 {
                            m[r][s] += w[k] * dp[r] * dp[s];
                            c[r][s] += w[k] * dq[r] * dp[s];
                        }
                    }
                }
            }
            let tr = m[0][0] + m[1][1];
            let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
            if tr <= 0.0 {
                // No other point: f_i is the translation to q_i.
                d.push([[1.0, 0.0], [0.0, 1.0]]);
                continue;
            }
            if det <= 1e-12 * tr * tr {
                // Tikhonov towards the identity: D (M + l I) = C + l I.
                let l = 1e-6 * tr;
                m[0][0] += l;
                m[1][1] += l;
                c[0][0] += l;
                c[1][1] += l;
            }
            let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
            let inv = [
                [m[1][1] / det, -m[0][1] / det],
                [-m[1][0] / det, m[0][0] / det],
            ];
            let mut di = [[0.0; 2]; 2];
            for r in 0..2 {
                for s in 0..2 {
                    di[r][s] = c[r][0] * inv[0][s] + c[r][1] * inv[1][s];
                }
            }
            d.push(di);
        }
        Idw {
            p: p.to_vec(),
            q: q.to_vec(),
            d,
            mu,
        }
    }

    /// The fitted local linear maps D_i (row-major).
    pub fn local_maps(&self) -> &[[[f64; 2]; 2]] {
        &self.d
    }
}

impl WarpMap for Idw {
    fn eval(&self, x: [f64; 2]) -> [f64; 2] {
        super::with_weights(|w| self.eval_with(x, w))
    }
}

impl Idw {
    /// `eval` with a scratch vector for the weights.
    fn eval_with(&self, x: [f64; 2], w: &mut Vec<f64>) -> [f64; 2] {
        if let Some(i) = weights(&self.p, x, self.mu, w) {
            return self.q[i];
        }
        let (mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0);
        for (i, wi) in w.iter().enumerate() {
            let (dx, dy) = (x[0] - self.p[i][0], x[1] - self.p[i][1]);
            let di = &self.d[i];
            sx += wi * (self.q[i][0] + di[0][0] * dx + di[0][1] * dy);
            sy += wi * (self.q[i][1] + di[1][0] * dx + di[1][1] * dy);
            sw += wi;
        }
        [sx / sw, sy / sw]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_and_recovers_a_linear_map_locally() {
        let p = [
            [10.0, 10.0],
            [50.0, 12.0],
            [30.0, 40.0],
            [70.0, 60.0],
            [5.0, 80.0],
        ];
        // q = A p + b: every D_i is A exactly (the least squares fit is exact) and f is A x + b.
        let a = [[1.1, 0.2], [-0.3, 0.9]];
        let q: Vec<[f64; 2]> = p
            .iter()
            .map(|x| {
                [
                    a[0][0] * x[0] + a[0][1] * x[1] + 3.0,
                    a[1][0] * x[0] + a[1][1] * x[1] - 2.0,
                ]
            })
            .collect();
        let f = Idw::fit(&p, &q, 2.0);
        for d in f.local_maps() {
            for r in 0..2 {
                for s in 0..2 {
                    assert!((d[r][s] - a[r][s]).abs() < 1e-12);
                }
            }
        }
        for (pi, qi) in p.iter().zip(&q) {
            assert_eq!(f.eval(*pi), *qi);
            let near = f.eval([pi[0] + 1e-9, pi[1]]);
            assert!((near[0] - qi[0]).abs() < 1e-6 && (near[1] - qi[1]).abs() < 1e-6);
        }
        let x = [33.0, 21.0];
        let y = f.eval(x);
        assert!((y[0] - (1.1 * 33.0 + 0.2 * 21.0 + 3.0)).abs() < 1e-9);
        assert!((y[1] - (-0.3 * 33.0 + 0.9 * 21.0 - 2.0)).abs() < 1e-9);
    }

    #[test]
    fn one_point_is_a_translation() {
        let f = Idw::fit(&[[1.0, 2.0]], &[[4.0, 6.0]], 2.0);
        let y = f.eval([10.0, 10.0]);
        assert!((y[0] - 13.0).abs() < 1e-5 && (y[1] - 14.0).abs() < 1e-5);
    }
}
