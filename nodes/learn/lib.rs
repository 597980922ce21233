//! Small neural networks (the modeling course's homework 3, insect classification): an MLP
//! classifier trained by SGD or Adam with hand-written reverse-mode gradients (`mlp`), an
//! Elman RNN reading the features as a sequence (`rnn`), tables
//! as classification data (`dataset`), training, prediction, and models saved as JSON.

pub mod classifier_predict;
pub mod classifier_train;
pub mod model;
pub use cgnodes_nn::{dataset, mlp, rnn};

use cgnodes_api::registry::Registry;

/// Registers this family's nodes, in the `learn` category.
pub fn register(r: &mut Registry) {
    r.with_category("learn", |r| {
        classifier_predict::register(r);
        classifier_train::register(r);
        model::register(r);
    });
}
