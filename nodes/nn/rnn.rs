//! An Elman recurrent network (Elman 1990, "Finding structure in time") reading a feature
//! vector as a sequence of scalars, the course's comparison model: with u_t = [x_t, h_{t-1}],
//!
//!   h_0 = 0,  h_t = g(W u_t + b)  (t = 1..T),  logits = V h_T + c,
//!
//! softmax cross-entropy on the logits, gradients by backpropagation through time written out
//! (Goodfellow et al., "Deep Learning", §10.2.2): dh_T = V^T dlogits, then for t = T..1
//! dz_t = dh_t ⊙ g'(z_t), dW += dz_t u_t^T, db += dz_t, dh_{t-1} = W_h^T dz_t.
//!
//! The network is stored as an `Mlp` of two layers (the cell W = [W_x | W_h] with its bias, the
//! output V, c), so `mlp::optimize` trains it and `Model` saves it unchanged.

use super::mlp::{argmax, train_classifier, Classifier, EpochLog, Mlp, TrainParams};
use cgnodes_api::rng::Pcg32;

/// Forward pass: the hidden states h_0..h_T and pre-activations z_1..z_T, then the logits.
fn forward(net: &Mlp, x: &[f64], hs: &mut Vec<Vec<f64>>, zs: &mut Vec<Vec<f64>>) -> Vec<f64> {
    let (cell, out) = (&net.layers[0], &net.layers[1]);
    let h_n = cell.outputs;
    hs.clear();
    zs.clear();
    hs.push(vec![0.0; h_n]);
    for &xt in x {
        let prev = hs.last().expect("h_0");
        let z: Vec<f64> = (0..h_n)
            .map(|o| {
                let row = &cell.weights[o * cell.inputs..(o + 1) * cell.inputs];
                cell.bias[o]
                    + row[0] * xt
                    + row[1..].iter().zip(prev).map(|(w, h)| w * h).sum::<f64>()
            })
            .collect();
        hs.push(z.iter().map(|&v| net.activation.apply(v)).collect());
        zs.push(z);
    }
    let h = hs.last().expect("h_T");
    (0..out.outputs)
        .map(|o| {
            let row = &out.weights[o * out.inputs..(o + 1) * out.inputs];
            out.bias[o] + row.iter().zip(h).map(|(w, v)| w * v).sum::<f64>()
        })
        .collect()
}

/// The class scores of feature vector `x`.
pub fn logits(net: &Mlp, x: &[f64]) -> Vec<f64> {
    forward(net, x, &mut Vec::new(), &mut Vec::new())
}

/// The most likely class of `x`.
pub fn predict(net: &Mlp, x: &[f64]) -> usize {
    argmax(&logits(net, x))
}

/// Mean softmax cross-entropy of the batch and its gradient by BPTT into `grads`.
pub fn loss_and_gradient(
    net: &Mlp,
    xs: &[&[f64]],
    ys: &[usize],
    grads: &mut [(Vec<f64>, Vec<f64>)],
) -> f64 {
    for (g, l) in grads.iter_mut().zip(&net.layers) {
        g.0.clear();
        g.0.resize(l.weights.len(), 0.0);
        g.1.clear();
        g.1.resize(l.bias.len(), 0.0);
    }
    let (cell, out) = (&net.layers[0], &net.layers[1]);
    let b = xs.len() as f64;
    let (mut hs, mut zs) = (Vec::new(), Vec::new());
    let mut loss = 0.0;
    for (x, &y) in xs.iter().zip(ys) {
        let lg = forward(net, x, &mut hs, &mut zs);
        let m = lg.iter().fold(f64::NEG_INFINITY, |a, &v| a.max(v));
        let sum: f64 = lg.iter().map(|v| (v - m).exp()).sum();
        loss += m + sum.ln() - lg[y];
        let dl: Vec<f64> = lg
            .iter()
            .enumerate()
            .map(|(k, v)| ((v - m).exp() / sum - f64::from(u8::from(k == y))) / b)
            .collect();
        let h_t = hs.last().expect("h_T");
        let mut dh = vec![0.0; cell.outputs];
        for (o, d) in dl.iter().enumerate() {
            grads[1].1[o] += d;
            let row = o * out.inputs;
            for (j, h) in h_t.iter().enumerate() {
                grads[1].0[row + j] += d * h;
                dh[j] += out.weights[row + j] * d;
            }
        }
        for t in (0..x.len()).rev() {
            let dz: Vec<f64> = dh
                .iter()
                .zip(&zs[t])
                .zip(&hs[t + 1])
                .map(|((d, &z), &a)| d * net.activation.derivative(z, a))
                .collect();
            let prev = &hs[t];
            let mut dprev = vec![0.0; cell.outputs];
            for (o, d) in dz.iter().enumerate() {
                grads[0].1[o] += d;
                let row = o * cell.inputs;
                grads[0].0[row] += d * x[t];
                for (j, h) in prev.iter().enumerate() {
                    grads[0].0[row + 1 + j] += d * h;
                    dprev[j] += cell.weights[row + 1 + j] * d;
                }
            }
            dh = dprev;
        }
    }
    loss / b
}

/// Trains an Elman network with `hidden` state units and `classes` outputs.
pub fn train(
    xs: &[Vec<f64>],
    ys: &[usize],
    classes: usize,
    test: Option<(&[Vec<f64>], &[usize])>,
    p: &TrainParams,
) -> (Mlp, Vec<EpochLog>) {
    let mut rng = Pcg32::new(p.seed, 27);
    let h = p.hidden.first().copied().unwrap_or(16);
    // Initialized as a [1 + h] -> h -> classes network: the cell's fan-in is x_t and h_{t-1}.
    let net = Mlp::new(&[1 + h, h, classes], p.activation, &mut rng);
    let score = Classifier {
        loss_and_gradient,
        accuracy,
    };
    train_classifier(net, &mut rng, (xs, ys), test, p, &score)
}

/// The fraction of `xs` classified as `ys` (0 for no samples).
fn accuracy(net: &Mlp, xs: &[Vec<f64>], ys: &[usize]) -> f64 {
    let ok = xs
        .iter()
        .zip(ys)
        .filter(|(a, &b)| predict(net, a) == b)
        .count();
    ok as f64 / xs.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::super::mlp::{normal, Activation, Optimizer};
    use super::*;

    #[test]
    fn bptt_gradients_match_finite_differences() {
        let mut rng = Pcg32::new(4, 4);
        let xs: Vec<Vec<f64>> = (0..4)
            .map(|_| (0..3).map(|_| normal(&mut rng)).collect())
            .collect();
        let ys = [0usize, 1, 2, 1];
        let bx: Vec<&[f64]> = xs.iter().map(Vec::as_slice).collect();
        for act in [Activation::Tanh, Activation::Sigmoid, Activation::Relu] {
            let mut net = Mlp::new(&[1 + 4, 4, 3], act, &mut rng);
            for b in &mut net.layers[0].bias {
                *b = 0.2;
            }
            let mut g = vec![(Vec::new(), Vec::new()); 2];
            loss_and_gradient(&net, &bx, &ys, &mut g);
            let mut scratch = g.clone();
            #[allow(clippy::needless_range_loop)] // l indexes the network copies too
            for l in 0..2 {
                for i in 0..net.layers[l].weights.len() {
                    let mut at = |d: f64| {
                        let mut q = net.clone();
                        q.layers[l].weights[i] += d;
                        loss_and_gradient(&q, &bx, &ys, &mut scratch)
                    };
                    let fd = (at(1e-6) - at(-1e-6)) / 2e-6;
                    let gi = g[l].0[i];
                    assert!(
                        (fd - gi).abs() < 1e-7 * (1.0 + gi.abs()),
                        "{act:?} {l} {i}: {fd} {gi}"
                    );
                }
            }
        }
    }

    #[test]
    fn learns_a_sequence_rule_reproducibly() {
        // Class 1 when the second feature exceeds the first: order matters.
        let mut rng = Pcg32::new(8, 8);
        let xs: Vec<Vec<f64>> = (0..80)
            .map(|_| vec![normal(&mut rng), normal(&mut rng)])
            .collect();
        let ys: Vec<usize> = xs.iter().map(|x| usize::from(x[1] > x[0])).collect();
        let p = TrainParams {
            hidden: vec![8],
            activation: Activation::Tanh,
            optimizer: Optimizer::Adam,
            learning_rate: 0.03,
            epochs: 150,
            batch_size: 16,
            seed: 2,
        };
        let (net, log) = train(&xs, &ys, 2, None, &p);
        assert!(
            log.last().unwrap().train_accuracy > 0.95,
            "{:?}",
            log.last()
        );
        assert!(log.last().unwrap().loss < 0.5 * log[0].loss);
        assert_eq!(train(&xs, &ys, 2, None, &p).0, net);
    }
}
