//! Small neural networks (the modeling course's homework 3, insect classification): an MLP
//! classifier trained by SGD or Adam with hand-written reverse-mode gradients (`mlp`), an
//! Elman RNN reading the features as a sequence (`rnn`), tables
//! as classification data (`dataset`), training, prediction, and models saved as JSON.

crate::node_domain! {
    category: "learn",
    nodes: [classifier_predict, classifier_train, model],
    modules: [dataset, mlp, rnn],
}
