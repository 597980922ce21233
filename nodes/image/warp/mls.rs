//! Moving least squares deformation (Schaefer, McPhail and Warren 2006, "Image deformation
//! using moving least squares", SIGGRAPH): at each point v the best affine, similarity or
//! rigid map l_v of the weighted control points, f(v) = l_v(v), with weights
//! w_i = 1 / |p_i - v|^(2 alpha) (eq. 1). With p* and q* the weighted centroids and
//! p^_i = p_i - p*, q^_i = q_i - q*:
//! - affine (eq. 5): f(v) = (v - p*) (sum w p^^T p^)^-1 sum w p^^T q^ + q*;
//! - similarity (eq. 7, written with complex numbers): f(v) = z (v - p*) + q* with
//!   z = sum w conj(p^) q^ / sum w |p^|^2;
//! - rigid (eq. 8): the rotation of z alone, f(v) = (z / |z|) (v - p*) + q*, which equals the
//!   paper's |v - p*| f_r(v) / |f_r(v)| + q*.
//!
//! At a control point the weight is infinite: f(p_i) = q_i is returned exactly.

use super::WarpMap;

/// The class of local maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MlsKind {
    /// General affine maps.
    Affine,
    /// Rotation, uniform scale and translation.
    Similarity,
    /// Rotation and translation.
    Rigid,
}

/// An MLS deformation (evaluated point by point; nothing is precomputed).
#[derive(Clone, Debug)]
pub struct Mls {
    p: Vec<[f64; 2]>,
    q: Vec<[f64; 2]>,
    kind: MlsKind,
    alpha: f64,
}

impl Mls {
    /// The deformation sending `p` to `q`.
    pub fn new(p: &[[f64; 2]], q: &[[f64; 2]], kind: MlsKind, alpha: f64) -> Mls {
        Mls {
            p: p.to_vec(),
            q: q.to_vec(),
            kind,
            alpha,
        }
    }
}

impl WarpMap for Mls {
    fn eval(&self, v: [f64; 2]) -> [f64; 2] {
        super::with_weights(|w| self.eval_with(v, w))
    }
}

impl Mls {
    /// `eval` with a scratch vector (empty) for the weights.
    fn eval_with(&self, v: [f64; 2], w: &mut Vec<f64>) -> [f64; 2] {
        let mut dmin = f64::INFINITY;
        for (i, p) in self.p.iter().enumerate() {
            let d2 = (v[0] - p[0]).powi(2) + (v[1] - p[1]).powi(2);
            if d2 == 0.0 {
                return self.q[i];
            }
            dmin = dmin.min(d2);
            w.push(d2);
        }
        // w_i = (dmin / d2_i)^alpha: the weights scaled so the largest is 1 (the scale cancels).
        let mut sw = 0.0;
        for x in w.iter_mut() {
            *x = if self.alpha == 1.0 {
                dmin / *x
            } else {
                (dmin / *x).powf(self.alpha)
            };
            sw += *x;
        }
        let (mut ps, mut qs) = ([0.0; 2], [0.0; 2]);
        for ((wi, p), q) in w.iter().zip(&self.p).zip(&self.q) {
            for k in 0..2 {
                ps[k] += wi * p[k];
                qs[k] += wi * q[k];
            }
        }
        for k in 0..2 {
            ps[k] /= sw;
            qs[k] /= sw;
        }
        let d = [v[0] - ps[0], v[1] - ps[1]];
        match self.kind {
            MlsKind::Affine => {
                // M = (sum w p^^T p^)^-1 (sum w p^^T q^), row vectors: f = d M + q*.
                let mut a = [[0.0; 2]; 2];
                let mut b = [[0.0; 2]; 2];
                for ((wi, p), q) in w.iter().zip(&self.p).zip(&self.q) {
                    let ph = [p[0] - ps[0], p[1] - ps[1]];
                    let qh = [q[0] - qs[0], q[1] - qs[1]];
                    for r in 0..2 {
                        for s in 0..2 {
                            a[r][s] += wi * ph[r] * ph[s];
                            b[r][s] += wi * ph[r] * qh[s];
                        }
                    }
                }
                let tr = a[0][0] + a[1][1];
                let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
                if det <= 1e-14 * tr * tr {
                    // The weighted points degenerate to a line here: translate only.
                    return [d[0] + qs[0], d[1] + qs[1]];
                }
                // e = d A^-1 (row vector), then f = e B + q*.
                let e = [
                    (d[0] * a[1][1] - d[1] * a[1][0]) / det,
                    (-d[0] * a[0][1] + d[1] * a[0][0]) / det,
                ];
                [
                    e[0] * b[0][0] + e[1] * b[1][0] + qs[0],
                    e[0] * b[0][1] + e[1] * b[1][1] + qs[1],
                ]
            }
            MlsKind::Similarity | MlsKind::Rigid => {
                // z = sum w conj(p^) q^ and mu = sum w |p^|^2.
                let (mut zr, mut zi, mut mu) = (0.0, 0.0, 0.0);
                for ((wi, p), q) in w.iter().zip(&self.p).zip(&self.q) {
                    let ph = [p[0] - ps[0], p[1] - ps[1]];
                    let qh = [q[0] - qs[0], q[1] - qs[1]];
                    zr += wi * (ph[0] * qh[0] + ph[1] * qh[1]);
                    zi += wi * (ph[0] * qh[1] - ph[1] * qh[0]);
                    mu += wi * (ph[0] * ph[0] + ph[1] * ph[1]);
                }
                let s = if self.kind == MlsKind::Rigid {
                    zr.hypot(zi)
                } else {
                    mu
                };
                let (a, b) = if s > 0.0 {
                    (zr / s, zi / s)
                } else {
                    (1.0, 0.0)
                };
                [a * d[0] - b * d[1] + qs[0], b * d[0] + a * d[1] + qs[1]]
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pts() -> Vec<[f64; 2]> {
        vec![
            [10.0, 10.0],
            [90.0, 15.0],
            [50.0, 70.0],
            [20.0, 95.0],
            [80.0, 80.0],
        ]
    }

    #[test]
    fn each_kind_interpolates_and_reproduces_its_own_class() {
        let p = pts();
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        // A similarity (scale 1.5, angle 0.3) and a rigid motion are reproduced by the kinds
        // that contain them.
        let sim: Vec<[f64; 2]> = p
            .iter()
            .map(|x| {
                [
                    1.5 * (c * x[0] - s * x[1]) + 4.0,
                    1.5 * (s * x[0] + c * x[1]) - 7.0,
                ]
            })
            .collect();
        let rig: Vec<[f64; 2]> = p
            .iter()
            .map(|x| [c * x[0] - s * x[1] + 4.0, s * x[0] + c * x[1] - 7.0])
            .collect();
        for (kind, q, scale) in [
            (MlsKind::Similarity, &sim, 1.5),
            (MlsKind::Rigid, &rig, 1.0),
            (MlsKind::Affine, &sim, 1.5),
        ] {
            let f = Mls::new(&p, q, kind, 1.0);
            for (pi, qi) in p.iter().zip(q.iter()) {
                assert_eq!(f.eval(*pi), *qi);
            }
            let x = [37.0, 52.0];
            let y = f.eval(x);
            let e = [
                scale * (c * x[0] - s * x[1]) + 4.0,
                scale * (s * x[0] + c * x[1]) - 7.0,
            ];
            assert!(
                (y[0] - e[0]).abs() < 1e-9 && (y[1] - e[1]).abs() < 1e-9,
                "{kind:?}"
            );
        }
    }
}
