//! cgnodes-nn: small neural networks and datasets, shared by the learning nodes (classifiers)
//! and the curve nodes (MLP curve fits, decision regions in plots): a multilayer perceptron
//! (`mlp`), a recurrent network (`rnn`) and dataset handling and prediction (`dataset`).

pub mod dataset;
pub mod mlp;
pub mod rnn;
