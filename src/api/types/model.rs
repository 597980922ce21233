//! `Model`: a trained classifier (the `model` socket), plain data that `model_save` writes
//! and `model_load` reads as JSON. The training and the forward pass are in `nodes/learn/`.

use serde::{Deserialize, Serialize};

/// A fully connected layer: y = W x + b, W stored row-major (`outputs` rows of `inputs`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DenseLayer {
    /// Input size.
    pub inputs: usize,
    /// Output size.
    pub outputs: usize,
    /// `outputs * inputs` weights, row-major.
    pub weights: Vec<f64>,
    /// `outputs` biases.
    pub bias: Vec<f64>,
}

/// A classifier: layers, the activation between them, the feature standardization and the
/// class labels of the output units.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Model {
    /// The architecture (`mlp`).
    pub kind: String,
    /// The hidden layers' activation (`relu`, `sigmoid`, `tanh`).
    pub activation: String,
    /// The layers in order; the last one's outputs are the class scores (softmax).
    pub layers: Vec<DenseLayer>,
    /// Names of the feature columns, in input order.
    pub features: Vec<String>,
    /// Name of the label column.
    pub label: String,
    /// The label value of each output unit.
    pub classes: Vec<i64>,
    /// Per-feature mean subtracted before the first layer (zeros without standardization).
    pub mean: Vec<f64>,
    /// Per-feature divisor applied after the mean (ones without standardization).
    pub scale: Vec<f64>,
}
