//! A multilayer perceptron classifier trained by minibatch gradient descent (Goodfellow,
//! Bengio & Courville, "Deep Learning", ch. 6 and 8): dense layers with ReLU, sigmoid or tanh
//! between them, softmax cross-entropy on the last, gradients by reverse mode written out for
//! these layers (their §6.5.4, algorithm 6.4):
//!
//!   forward:  z_l = W_l a_{l-1} + b_l,  a_l = g(z_l);  p = softmax(z_L);
//!   backward: dz_L = (p - onehot(y)) / B;  dW_l = dz_l a_{l-1}^T,  db_l = dz_l;
//!             dz_{l-1} = (W_l^T dz_l) * g'(z_{l-1}).
//!
//! He initialization for ReLU (He et al. 2015), Xavier/Glorot for sigmoid and tanh (Glorot &
//! Bengio 2010), biases zero; SGD or Adam (Kingma & Ba 2015, algorithm 1, beta 0.9 / 0.999,
//! eps 1e-8). Small dense layers need no tensor library: a layer is a row-major weight
//! vector. One thread, so a seed fixes every number.

use cgnodes_api::node::Choice;
use cgnodes_api::rng::Pcg32;
use cgnodes_api::types::DenseLayer;

/// The hidden layers' activation g.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Activation {
    /// max(0, z).
    Relu,
    /// 1 / (1 + e^-z).
    Sigmoid,
    /// tanh z.
    Tanh,
}

impl Choice for Activation {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("relu", Activation::Relu),
        ("sigmoid", Activation::Sigmoid),
        ("tanh", Activation::Tanh),
    ];
}

impl Activation {
    /// The socket name.
    pub fn name(self) -> &'static str {
        Self::CHOICES
            .iter()
            .find(|(_, a)| *a == self)
            .map_or("?", |(n, _)| n)
    }

    /// g(z).
    pub fn apply(self, z: f64) -> f64 {
        match self {
            Activation::Relu => z.max(0.0),
            Activation::Sigmoid => 1.0 / (1.0 + (-z).exp()),
            Activation::Tanh => z.tanh(),
        }
    }

    /// g'(z) from z and a = g(z).
    pub fn derivative(self, z: f64, a: f64) -> f64 {
        match self {
            Activation::Relu => {
                if z > 0.0 {
                    1.0
                } else {
                    0.0
                }
            }
            Activation::Sigmoid => a * (1.0 - a),
            Activation::Tanh => 1.0 - a * a,
        }
    }
}

/// The update rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Optimizer {
    /// Adam.
    Adam,
    /// Plain stochastic gradient descent.
    Sgd,
}

impl Choice for Optimizer {
    const CHOICES: &'static [(&'static str, Self)] =
        &[("adam", Optimizer::Adam), ("sgd", Optimizer::Sgd)];
}

/// A network: dense layers and the activation between them.
#[derive(Clone, Debug, PartialEq)]
pub struct Mlp {
    /// The layers, input first.
    pub layers: Vec<DenseLayer>,
    /// The hidden activation.
    pub activation: Activation,
}

/// A uniform number in [0, 1) with 53 bits.
pub fn uniform(rng: &mut Pcg32) -> f64 {
    let hi = u64::from(rng.next_u32()) << 21;
    let lo = u64::from(rng.next_u32() >> 11);
    ((hi | lo) as f64) / (1u64 << 53) as f64
}

/// A standard normal number (Box-Muller).
pub fn normal(rng: &mut Pcg32) -> f64 {
    let u1 = 1.0 - uniform(rng);
    let u2 = uniform(rng);
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

impl Mlp {
    /// Random weights for layer sizes `sizes` (inputs, hidden..., classes).
    pub fn new(sizes: &[usize], activation: Activation, rng: &mut Pcg32) -> Mlp {
        let layers = sizes
            .windows(2)
            .map(|w| {
                let (n_in, n_out) = (w[0], w[1]);
                let sd = match activation {
                    Activation::Relu => (2.0 / n_in as f64).sqrt(),
                    _ => (2.0 / (n_in + n_out) as f64).sqrt(),
                };
                DenseLayer {
                    inputs: n_in,
                    outputs: n_out,
                    weights: (0..n_in * n_out).map(|_| sd * normal(rng)).collect(),
                    bias: vec![0.0; n_out],
                }
            })
            .collect();
        Mlp { layers, activation }
    }

    /// Pre-activations z_l and activations a_l of every layer for input `x` (a_0 = x; the
    /// last layer's a is its z, the logits).
    fn forward_all(&self, x: &[f64], zs: &mut Vec<Vec<f64>>, acts: &mut Vec<Vec<f64>>) {
        zs.clear();
        acts.clear();
        acts.push(x.to_vec());
        let last = self.layers.len() - 1;
        for (l, layer) in self.layers.iter().enumerate() {
            let a = &acts[l];
            let z: Vec<f64> = (0..layer.outputs)
                .map(|o| {
                    let row = &layer.weights[o * layer.inputs..(o + 1) * layer.inputs];
                    layer.bias[o] + row.iter().zip(a).map(|(w, v)| w * v).sum::<f64>()
                })
                .collect();
            let next = if l == last {
                z.clone()
            } else {
                z.iter().map(|&v| self.activation.apply(v)).collect()
            };
            zs.push(z);
            acts.push(next);
        }
    }

    /// The class scores (logits) of `x`.
    pub fn logits(&self, x: &[f64]) -> Vec<f64> {
        let (mut zs, mut acts) = (Vec::new(), Vec::new());
        self.forward_all(x, &mut zs, &mut acts);
        acts.pop().unwrap_or_default()
    }

    /// The most likely class of `x`.
    pub fn predict(&self, x: &[f64]) -> usize {
        argmax(&self.logits(x))
    }

    /// Mean softmax cross-entropy of the batch and its gradient, accumulated into `grads`
    /// (one (dW, db) per layer, zeroed here).
    pub fn loss_and_gradient(
        &self,
        xs: &[&[f64]],
        ys: &[usize],
        grads: &mut [(Vec<f64>, Vec<f64>)],
    ) -> f64 {
        let b = xs.len() as f64;
        self.backprop(xs, grads, |k, logits| {
            let y = ys[k];
            let m = logits.iter().fold(f64::NEG_INFINITY, |a, &v| a.max(v));
            let sum: f64 = logits.iter().map(|v| (v - m).exp()).sum();
            let dz = logits
                .iter()
                .enumerate()
                .map(|(j, v)| ((v - m).exp() / sum - f64::from(u8::from(j == y))) / b)
                .collect();
            (m + sum.ln() - logits[y], dz)
        })
    }

    /// Mean over the batch of 1/2 |f(x) - y|^2 (a regression head: the last layer's outputs
    /// as they are) and its gradient, accumulated into `grads`.
    pub fn squared_error_and_gradient(
        &self,
        xs: &[&[f64]],
        ys: &[&[f64]],
        grads: &mut [(Vec<f64>, Vec<f64>)],
    ) -> f64 {
        let b = xs.len() as f64;
        self.backprop(xs, grads, |k, out| {
            let r: Vec<f64> = out.iter().zip(ys[k]).map(|(o, y)| o - y).collect();
            (
                0.5 * r.iter().map(|v| v * v).sum::<f64>(),
                r.iter().map(|v| v / b).collect(),
            )
        })
    }

    /// Forward and backward passes over the batch; `head(k, outputs)` gives sample k's loss
    /// and the gradient of the batch loss with respect to the last layer's outputs.
    fn backprop(
        &self,
        xs: &[&[f64]],
        grads: &mut [(Vec<f64>, Vec<f64>)],
        mut head: impl FnMut(usize, &[f64]) -> (f64, Vec<f64>),
    ) -> f64 {
        for (g, l) in grads.iter_mut().zip(&self.layers) {
            g.0.clear();
            g.0.resize(l.weights.len(), 0.0);
            g.1.clear();
            g.1.resize(l.bias.len(), 0.0);
        }
        let (mut zs, mut acts) = (Vec::new(), Vec::new());
        let mut loss = 0.0;
        for (k, x) in xs.iter().enumerate() {
            self.forward_all(x, &mut zs, &mut acts);
            let (l_k, mut dz) = head(k, acts.last().expect("at least one layer"));
            loss += l_k;
            for l in (0..self.layers.len()).rev() {
                let layer = &self.layers[l];
                let a_prev = &acts[l];
                let (gw, gb) = &mut grads[l];
                for (o, d) in dz.iter().enumerate() {
                    gb[o] += d;
                    let row = &mut gw[o * layer.inputs..(o + 1) * layer.inputs];
                    for (g, a) in row.iter_mut().zip(a_prev) {
                        *g += d * a;
                    }
                }
                if l > 0 {
                    let mut da = vec![0.0; layer.inputs];
                    for (o, d) in dz.iter().enumerate() {
                        let row = &layer.weights[o * layer.inputs..(o + 1) * layer.inputs];
                        for (s, w) in da.iter_mut().zip(row) {
                            *s += w * d;
                        }
                    }
                    dz = da
                        .iter()
                        .zip(&zs[l - 1])
                        .zip(&acts[l])
                        .map(|((d, &z), &a)| d * self.activation.derivative(z, a))
                        .collect();
                }
            }
        }
        loss / xs.len().max(1) as f64
    }
}

/// The index of the largest value (the first on ties).
pub fn argmax(v: &[f64]) -> usize {
    let mut best = 0;
    for (i, x) in v.iter().enumerate() {
        if *x > v[best] {
            best = i;
        }
    }
    best
}

/// Training settings.
#[derive(Clone, Debug, PartialEq)]
pub struct TrainParams {
    /// Hidden layer sizes.
    pub hidden: Vec<usize>,
    /// Hidden activation.
    pub activation: Activation,
    /// Update rule.
    pub optimizer: Optimizer,
    /// Step size.
    pub learning_rate: f64,
    /// Passes over the data.
    pub epochs: usize,
    /// Samples per step.
    pub batch_size: usize,
    /// Seed of the initialization and the shuffling.
    pub seed: u64,
}

/// One epoch's record: mean training loss over its batches and the accuracies after it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EpochLog {
    /// Mean of the batches' losses.
    pub loss: f64,
    /// Training accuracy after the epoch.
    pub train_accuracy: f64,
    /// Test accuracy after the epoch (NaN without test data).
    pub test_accuracy: f64,
}

/// The fraction of `xs` classified as `ys`.
pub fn accuracy(net: &Mlp, xs: &[Vec<f64>], ys: &[usize]) -> f64 {
    if xs.is_empty() {
        return f64::NAN;
    }
    let ok = xs
        .iter()
        .zip(ys)
        .filter(|(x, &y)| net.predict(x) == y)
        .count();
    ok as f64 / xs.len() as f64
}

/// Minibatch optimization of `net` over `n` samples: `batch_loss(net, indices, grads)`
/// returns a batch's loss and fills its gradient, `after_epoch(net, mean loss)` runs after
/// every pass. The samples are reshuffled every epoch (Fisher-Yates) with `rng`.
pub fn optimize(
    net: &mut Mlp,
    n: usize,
    p: &TrainParams,
    rng: &mut Pcg32,
    mut batch_loss: impl FnMut(&Mlp, &[usize], &mut [(Vec<f64>, Vec<f64>)]) -> f64,
    mut after_epoch: impl FnMut(&Mlp, f64),
) {
    let mut grads: Vec<(Vec<f64>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); net.layers.len()];
    // Adam's moments, one (weights, biases) pair per layer for m and for v.
    let zeros = |net: &Mlp| -> Vec<(Vec<f64>, Vec<f64>)> {
        net.layers
            .iter()
            .map(|l| (vec![0.0; l.weights.len()], vec![0.0; l.bias.len()]))
            .collect()
    };
    let (mut m, mut v) = (zeros(net), zeros(net));
    let (b1, b2, eps) = (0.9f64, 0.999f64, 1e-8);
    let mut step = 0i32;
    let mut order: Vec<usize> = (0..n).collect();
    let bs = p.batch_size.max(1);
    for _ in 0..p.epochs {
        for i in (1..order.len()).rev() {
            let j = (uniform(rng) * (i + 1) as f64) as usize;
            order.swap(i, j.min(i));
        }
        let (mut total, mut batches) = (0.0, 0usize);
        for chunk in order.chunks(bs) {
            total += batch_loss(net, chunk, &mut grads);
            batches += 1;
            step = step.saturating_add(1);
            let (c1, c2) = (1.0 - b1.powi(step), 1.0 - b2.powi(step));
            for (l, layer) in net.layers.iter_mut().enumerate() {
                let params = [&mut layer.weights, &mut layer.bias];
                let gs = [&grads[l].0, &grads[l].1];
                let (ml, vl) = (&mut m[l], &mut v[l]);
                let ms = [&mut ml.0, &mut ml.1];
                let vs = [&mut vl.0, &mut vl.1];
                for (((w, g), mk), vk) in params.into_iter().zip(gs).zip(ms).zip(vs) {
                    for i in 0..w.len() {
                        match p.optimizer {
                            Optimizer::Sgd => w[i] -= p.learning_rate * g[i],
                            Optimizer::Adam => {
                                mk[i] = b1 * mk[i] + (1.0 - b1) * g[i];
                                vk[i] = b2 * vk[i] + (1.0 - b2) * g[i] * g[i];
                                let mh = mk[i] / c1;
                                let vh = vk[i] / c2;
                                w[i] -= p.learning_rate * mh / (vh.sqrt() + eps);
                            }
                        }
                    }
                }
            }
        }
        after_epoch(net, total / batches.max(1) as f64);
    }
}

/// Trains a network with `classes` outputs on (xs, ys), ys in 0..classes; `test` is
/// evaluated after every epoch.
pub fn train(
    xs: &[Vec<f64>],
    ys: &[usize],
    classes: usize,
    test: Option<(&[Vec<f64>], &[usize])>,
    p: &TrainParams,
) -> (Mlp, Vec<EpochLog>) {
    let mut rng = Pcg32::new(p.seed, 26);
    let mut sizes = vec![xs.first().map_or(0, Vec::len)];
    sizes.extend(&p.hidden);
    sizes.push(classes);
    let net = Mlp::new(&sizes, p.activation, &mut rng);
    let score = Classifier {
        loss_and_gradient: |net, xs, ys, grads| net.loss_and_gradient(xs, ys, grads),
        accuracy,
    };
    train_classifier(net, &mut rng, (xs, ys), test, p, &score)
}

/// Mean loss of a batch of inputs and labels, its gradient written into the per-layer
/// (weights, biases).
pub type LossAndGradient = fn(&Mlp, &[&[f64]], &[usize], &mut [(Vec<f64>, Vec<f64>)]) -> f64;

/// How a classifier stored as an `Mlp` scores a batch and a whole set: the multilayer
/// perceptron and the Elman network (`rnn`) differ only in these two functions.
pub struct Classifier {
    /// Mean loss of a batch, its gradient written into the per-layer (weights, biases).
    pub loss_and_gradient: LossAndGradient,
    /// The fraction of a set classified correctly.
    pub accuracy: fn(&Mlp, &[Vec<f64>], &[usize]) -> f64,
}

/// Trains the initialized classifier `net` on `(xs, ys)` with `optimize`, logging the mean
/// loss and the train and test accuracies after every epoch.
pub fn train_classifier(
    mut net: Mlp,
    rng: &mut Pcg32,
    (xs, ys): (&[Vec<f64>], &[usize]),
    test: Option<(&[Vec<f64>], &[usize])>,
    p: &TrainParams,
    score: &Classifier,
) -> (Mlp, Vec<EpochLog>) {
    let mut log = Vec::with_capacity(p.epochs);
    optimize(
        &mut net,
        xs.len(),
        p,
        rng,
        |net, idx, grads| {
            let bx: Vec<&[f64]> = idx.iter().map(|&i| xs[i].as_slice()).collect();
            let by: Vec<usize> = idx.iter().map(|&i| ys[i]).collect();
            (score.loss_and_gradient)(net, &bx, &by, grads)
        },
        |net, loss| {
            log.push(EpochLog {
                loss,
                train_accuracy: (score.accuracy)(net, xs, ys),
                test_accuracy: test.map_or(f64::NAN, |(tx, ty)| (score.accuracy)(net, tx, ty)),
            })
        },
    );
    (net, log)
}

/// Fits a regression network xs -> ys (squared error); returns it and the mean loss of
/// every epoch.
pub fn fit_regression(xs: &[Vec<f64>], ys: &[Vec<f64>], p: &TrainParams) -> (Mlp, Vec<f64>) {
    let mut rng = Pcg32::new(p.seed, 26);
    let mut sizes = vec![xs.first().map_or(0, Vec::len)];
    sizes.extend(&p.hidden);
    sizes.push(ys.first().map_or(0, Vec::len));
    let mut net = Mlp::new(&sizes, p.activation, &mut rng);
    let mut losses = Vec::with_capacity(p.epochs);
    optimize(
        &mut net,
        xs.len(),
        p,
        &mut rng,
        |net, idx, grads| {
            let bx: Vec<&[f64]> = idx.iter().map(|&i| xs[i].as_slice()).collect();
            let by: Vec<&[f64]> = idx.iter().map(|&i| ys[i].as_slice()).collect();
            net.squared_error_and_gradient(&bx, &by, grads)
        },
        |_, loss| losses.push(loss),
    );
    (net, losses)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toy() -> (Vec<Vec<f64>>, Vec<usize>) {
        // Two classes on either side of the line x + 2y = 1, away from it.
        let mut rng = Pcg32::new(5, 1);
        let (mut xs, mut ys) = (Vec::new(), Vec::new());
        while xs.len() < 60 {
            let p = [4.0 * uniform(&mut rng) - 2.0, 4.0 * uniform(&mut rng) - 2.0];
            let s = p[0] + 2.0 * p[1] - 1.0;
            if s.abs() > 0.3 {
                xs.push(p.to_vec());
                ys.push(usize::from(s > 0.0));
            }
        }
        (xs, ys)
    }

    #[test]
    fn gradients_match_finite_differences_for_every_activation() {
        let mut rng = Pcg32::new(3, 7);
        let xs: Vec<Vec<f64>> = (0..5)
            .map(|_| (0..3).map(|_| normal(&mut rng)).collect())
            .collect();
        let ys = [0usize, 2, 1, 2, 0];
        let bx: Vec<&[f64]> = xs.iter().map(Vec::as_slice).collect();
        for act in [Activation::Relu, Activation::Sigmoid, Activation::Tanh] {
            let mut net = Mlp::new(&[3, 4, 5, 3], act, &mut rng);
            // Biases away from zero so no ReLU sits at its kink.
            for l in &mut net.layers {
                for b in &mut l.bias {
                    *b = 0.1 + 0.3 * uniform(&mut rng);
                }
            }
            let mut grads = vec![(Vec::new(), Vec::new()); 3];
            net.loss_and_gradient(&bx, &ys, &mut grads);
            let h = 1e-6;
            let mut scratch = grads.clone();
            #[allow(clippy::needless_range_loop)] // l indexes the network copies too
            for l in 0..3 {
                for which in 0..2 {
                    let n = if which == 0 {
                        net.layers[l].weights.len()
                    } else {
                        net.layers[l].bias.len()
                    };
                    for i in 0..n {
                        let mut loss_at = |d: f64| {
                            let mut q = net.clone();
                            if which == 0 {
                                q.layers[l].weights[i] += d;
                            } else {
                                q.layers[l].bias[i] += d;
                            }
                            q.loss_and_gradient(&bx, &ys, &mut scratch)
                        };
                        let fd = (loss_at(h) - loss_at(-h)) / (2.0 * h);
                        let g = if which == 0 {
                            grads[l].0[i]
                        } else {
                            grads[l].1[i]
                        };
                        assert!(
                            (fd - g).abs() < 1e-7 * (1.0 + g.abs()),
                            "{act:?} layer {l} {which} {i}: {fd} vs {g}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn squared_error_gradient_matches_finite_differences() {
        let mut rng = Pcg32::new(9, 2);
        let net = Mlp::new(&[1, 6, 2], Activation::Tanh, &mut rng);
        let xs = [[0.1], [0.5], [0.9]];
        let ys = [[1.0, -1.0], [0.0, 2.0], [0.5, 0.5]];
        let bx: Vec<&[f64]> = xs.iter().map(|x| x.as_slice()).collect();
        let by: Vec<&[f64]> = ys.iter().map(|y| y.as_slice()).collect();
        let mut g = vec![(Vec::new(), Vec::new()); 2];
        net.squared_error_and_gradient(&bx, &by, &mut g);
        let mut scratch = g.clone();
        for i in 0..net.layers[0].weights.len() {
            let mut at = |d: f64| {
                let mut q = net.clone();
                q.layers[0].weights[i] += d;
                q.squared_error_and_gradient(&bx, &by, &mut scratch)
            };
            let fd = (at(1e-6) - at(-1e-6)) / 2e-6;
            assert!(
                (fd - g[0].0[i]).abs() < 1e-7 * (1.0 + fd.abs()),
                "{fd} {}",
                g[0].0[i]
            );
        }
    }

    #[test]
    fn separable_data_is_learned_exactly_and_reproducibly() {
        let (xs, ys) = toy();
        let p = TrainParams {
            hidden: vec![8],
            activation: Activation::Tanh,
            optimizer: Optimizer::Adam,
            learning_rate: 0.05,
            epochs: 200,
            batch_size: 16,
            seed: 11,
        };
        let (net, log) = train(&xs, &ys, 2, None, &p);
        assert_eq!(accuracy(&net, &xs, &ys), 1.0);
        assert!(log.last().unwrap().loss < 0.5 * log[0].loss);
        let (again, _) = train(&xs, &ys, 2, None, &p);
        assert_eq!(net, again);
        let other = train(
            &xs,
            &ys,
            2,
            None,
            &TrainParams {
                seed: 12,
                ..p.clone()
            },
        )
        .0;
        assert_ne!(net, other);
        // SGD with sigmoid also separates it.
        let sgd = TrainParams {
            activation: Activation::Sigmoid,
            optimizer: Optimizer::Sgd,
            learning_rate: 0.5,
            epochs: 300,
            ..p
        };
        assert_eq!(accuracy(&train(&xs, &ys, 2, None, &sgd).0, &xs, &ys), 1.0);
    }
}
