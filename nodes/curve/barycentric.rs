//! Polynomial interpolation in the barycentric form (Berrut & Trefethen 2004, "Barycentric
//! Lagrange interpolation", SIAM Review 46(3)): with weights w_j = 1 / prod_{k != j}(t_j - t_k),
//!
//!   p(t) = sum_j w_j f_j / (t - t_j)  /  sum_j w_j / (t - t_j)        (their eq. 4.2),
//!
//! which costs O(n) per evaluation after O(n^2) for the weights and is forward stable for
//! any nodes with a good Lebesgue constant (Higham 2004), where solving the Vandermonde system
//! for monomial coefficients loses digits with its condition number (exponential in n).
//! The nodes are scaled to an interval of length 4 before the products (their §7, "the
//! capacity"), so the weights neither overflow nor underflow for hundreds of nodes; the
//! common factor cancels in the quotient.

/// A polynomial through points (t_j, f_j) with values in R^D.
#[derive(Clone, Debug)]
pub struct Barycentric<const D: usize> {
    t: Vec<f64>,
    f: Vec<[f64; D]>,
    w: Vec<f64>,
}

/// The weights of eq. (3.2) for distinct nodes `t`, scaled so the largest has magnitude 1.
pub fn weights(t: &[f64]) -> Vec<f64> {
    let (lo, hi) = t
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let c = if hi > lo { 4.0 / (hi - lo) } else { 1.0 };
    let mut w: Vec<f64> = (0..t.len())
        .map(|j| {
            let p: f64 = (0..t.len())
                .filter(|&k| k != j)
                .map(|k| c * (t[j] - t[k]))
                .product();
            1.0 / p
        })
        .collect();
    let m = w.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if m > 0.0 && m.is_finite() {
        for x in &mut w {
            *x /= m;
        }
    }
    w
}

impl<const D: usize> Barycentric<D> {
    /// The interpolant of `f` at the distinct nodes `t` (same length, at least one).
    pub fn new(t: &[f64], f: &[[f64; D]]) -> Barycentric<D> {
        Barycentric {
            t: t.to_vec(),
            f: f.to_vec(),
            w: weights(t),
        }
    }

    /// p(x); exactly f_j at a node.
    pub fn eval(&self, x: f64) -> [f64; D] {
        let mut num = [0.0; D];
        let mut den = 0.0;
        for ((tj, fj), wj) in self.t.iter().zip(&self.f).zip(&self.w) {
            let d = x - tj;
            if d == 0.0 {
                return *fj;
            }
            let c = wj / d;
            den += c;
            for k in 0..D {
                num[k] += c * fj[k];
            }
        }
        num.map(|v| v / den)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reproduces_a_cubic_and_its_nodes() {
        let t = [0.0, 0.1, 0.5, 0.7, 1.0];
        let f: Vec<[f64; 1]> = t.iter().map(|&x| [2.0 * x * x * x - x + 0.5]).collect();
        let p = Barycentric::new(&t, &f);
        for (x, y) in t.iter().zip(&f) {
            assert_eq!(p.eval(*x), *y);
        }
        for k in 0..=20 {
            let x = k as f64 / 20.0;
            let want = 2.0 * x * x * x - x + 0.5;
            assert!((p.eval(x)[0] - want).abs() < 1e-14, "{x}");
        }
    }

    #[test]
    fn hundreds_of_chebyshev_nodes_stay_finite_and_accurate() {
        // Runge's function at 400 Chebyshev points: the interpolant converges geometrically.
        let n = 400;
        let t: Vec<f64> = (0..n)
            .map(|j| (std::f64::consts::PI * j as f64 / (n - 1) as f64).cos())
            .collect();
        let runge = |x: f64| 1.0 / (1.0 + 25.0 * x * x);
        let f: Vec<[f64; 1]> = t.iter().map(|&x| [runge(x)]).collect();
        let p = Barycentric::new(&t, &f);
        assert!(p.w.iter().all(|w| w.is_finite() && *w != 0.0));
        let err = (0..1001)
            .map(|k| {
                let x = -1.0 + 2.0 * k as f64 / 1000.0;
                (p.eval(x)[0] - runge(x)).abs()
            })
            .fold(0.0, f64::max);
        assert!(err < 1e-12, "{err}");
    }
}
