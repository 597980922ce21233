//! A curve fitted by a small network t -> (x, y) (the `mlp` method of `curve_interpolate`,
//! GAMES102 homework 2's neural-network variant): tanh hidden layers, a linear output,
//! squared error, Adam (learning rate 0.01) on the whole point set per step. The parameter
//! is mapped to [0, 1] and the coordinates standardized before training, so one learning
//! rate suits any drawing's size. An approximation, not an interpolation: how close it comes
//! to the points depends on the width and the epochs (`nodes/learn/mlp.rs`).

use cgnodes_nn::mlp::{fit_regression, Activation, Mlp, Optimizer, TrainParams};

/// A trained curve network with its input and output scaling.
#[derive(Clone, Debug)]
pub struct CurveMlp {
    net: Mlp,
    t0: f64,
    span: f64,
    mean: [f64; 2],
    scale: [f64; 2],
    /// The mean squared-error loss (on standardized coordinates) after every epoch.
    pub losses: Vec<f64>,
}

impl CurveMlp {
    /// Trains on points `p` at parameters `t` (increasing, at least two).
    pub fn fit(p: &[[f64; 2]], t: &[f64], hidden: &[usize], epochs: usize, seed: u64) -> CurveMlp {
        let n = p.len() as f64;
        let mean = [0, 1].map(|k| p.iter().map(|q| q[k]).sum::<f64>() / n);
        let scale = [0, 1].map(|k| {
            let s = (p.iter().map(|q| (q[k] - mean[k]).powi(2)).sum::<f64>() / n).sqrt();
            if s > 0.0 {
                s
            } else {
                1.0
            }
        });
        let (t0, span) = (t[0], (t[t.len() - 1] - t[0]).max(f64::MIN_POSITIVE));
        let xs: Vec<Vec<f64>> = t.iter().map(|&v| vec![(v - t0) / span]).collect();
        let ys: Vec<Vec<f64>> = p
            .iter()
            .map(|q| vec![(q[0] - mean[0]) / scale[0], (q[1] - mean[1]) / scale[1]])
            .collect();
        let params = TrainParams {
            hidden: hidden.to_vec(),
            activation: Activation::Tanh,
            optimizer: Optimizer::Adam,
            learning_rate: 0.01,
            epochs,
            batch_size: p.len(),
            seed,
        };
        let (net, losses) = fit_regression(&xs, &ys, &params);
        CurveMlp {
            net,
            t0,
            span,
            mean,
            scale,
            losses,
        }
    }

    /// The curve's point at parameter `x`.
    pub fn eval(&self, x: f64) -> [f64; 2] {
        let o = self.net.logits(&[(x - self.t0) / self.span]);
        [0, 1].map(|k| o[k] * self.scale[k] + self.mean[k])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn training_lowers_the_loss_and_approaches_the_points() {
        let p: Vec<[f64; 2]> = (0..8)
            .map(|i| {
                let a = i as f64 / 7.0 * 3.0;
                [a.cos() * 10.0, a.sin() * 10.0]
            })
            .collect();
        let t: Vec<f64> = (0..8).map(|i| i as f64 / 7.0).collect();
        let c = CurveMlp::fit(&p, &t, &[16], 1500, 1);
        let (first, last) = (c.losses[0], *c.losses.last().unwrap());
        assert!(last < 0.01 * first, "{first} -> {last}");
        let worst = p
            .iter()
            .zip(&t)
            .map(|(q, &x)| {
                let v = c.eval(x);
                (v[0] - q[0]).hypot(v[1] - q[1])
            })
            .fold(0.0, f64::max);
        assert!(worst < 1.0, "{worst}");
        // The same seed, the same curve.
        let again = CurveMlp::fit(&p, &t, &[16], 1500, 1);
        assert_eq!(again.eval(0.37), c.eval(0.37));
    }
}
