//! `classifier_train`: trains a multilayer perceptron or an Elman RNN classifier on a table
//! (the modeling course's insect classification, homework 3): every column but the label
//! column is a feature. The networks and their training are in `mlp.rs` and `rnn.rs`.

use super::dataset::{self, features, int_labels, label_index, standardization, TableError};
use super::mlp::{train, Activation, EpochLog, Optimizer, TrainParams};
use cgnodes_api::prelude::*;

/// The network (the `model` input).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Architecture {
    /// A multilayer perceptron (`mlp.rs`).
    Mlp,
    /// An Elman network reading the features as a sequence (`rnn.rs`).
    Rnn,
}

impl Choice for Architecture {
    const CHOICES: &'static [(&'static str, Self)] =
        &[("mlp", Architecture::Mlp), ("rnn", Architecture::Rnn)];
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Trains an MLP classifier (softmax cross-entropy, SGD or Adam) on a table with an integer label column.");
    b.add_input::<Table>("train")
        .doc("Training rows: feature columns and a label column.");
    b.add_input::<Table>("test")
        .optional()
        .doc("Rows evaluated after every epoch (same columns).");
    b.add_input::<String>("label_column")
        .default("")
        .doc("The label column: a header name or a 0-based index; empty = the last column.");
    b.add_choice::<Architecture>("model")
        .doc("mlp, or rnn (an Elman network reading the features one by one as a sequence).");
    b.add_input::<Vec<i64>>("hidden")
        .default(Value::from(vec![16i64, 16]))
        .doc("Hidden layer sizes, e.g. [16, 16]; rnn: one size, its state.");
    b.add_choice::<Activation>("activation")
        .doc("relu, sigmoid or tanh.");
    b.add_choice::<Optimizer>("optimizer").doc("adam or sgd.");
    b.add_input::<f64>("learning_rate")
        .default(1e-3)
        .range(1e-9, 10.0);
    b.add_input::<i64>("epochs").default(200).range(1.0, 1e6);
    b.add_input::<i64>("batch_size").default(32).range(1.0, 1e7);
    b.add_input::<i64>("seed").default(0).min(0.0);
    b.add_input::<bool>("standardize")
        .default(true)
        .doc("Scale each feature to zero mean and unit variance (stored in the model).");
    b.add_output::<Model>("model");
    b.add_output::<Table>("log")
        .doc("Per epoch: epoch, loss, train_accuracy, test_accuracy (NaN without test); meta train_seconds.");
}

/// Feature names, feature rows and labels.
type Labelled = (Vec<String>, Vec<Vec<f64>>, Vec<i64>);

/// Why a training table cannot be used, by the socket it concerns.
#[derive(Debug, thiserror::Error)]
enum LabelledError {
    /// The label column is not integers (`label_column`).
    #[error("{0}")]
    Labels(TableError),
    /// A feature value (`train`).
    #[error("{0}")]
    Features(TableError),
    /// Only the label column (`train`).
    #[error("no feature column besides the label column")]
    NoFeatures,
    /// No rows (`train`).
    #[error("no rows")]
    NoRows,
}

impl LabelledError {
    fn into_node_error(self) -> NodeError {
        let socket = match self {
            LabelledError::Labels(_) => "label_column",
            _ => "train",
        };
        NodeError::invalid(socket, self.to_string())
    }
}

/// Reads `t` as (features, labels) with the label column at `c`.
fn labelled(t: &Table, c: usize) -> Result<Labelled, LabelledError> {
    let names: Vec<String> = t
        .columns
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != c)
        .map(|(_, (n, _))| n.clone())
        .collect();
    if names.is_empty() {
        return Err(LabelledError::NoFeatures);
    }
    let x = features(t, &names).map_err(LabelledError::Features)?;
    let y = int_labels(t, c).map_err(LabelledError::Labels)?;
    if x.is_empty() {
        return Err(LabelledError::NoRows);
    }
    Ok((names, x, y))
}

/// The training classes (sorted distinct labels) and every row's class index.
fn classes_of(y: &[i64]) -> Result<(Vec<i64>, Vec<usize>), NodeError> {
    let mut classes = y.to_vec();
    classes.sort_unstable();
    classes.dedup();
    if classes.len() < 2 {
        return Err(NodeError::invalid("train", "needs at least 2 classes"));
    }
    let yi = y
        .iter()
        .map(|v| classes.binary_search(v).unwrap_or(0))
        .collect();
    Ok((classes, yi))
}

/// The features and labels a trained model is judged on after every epoch.
type TestSet = (Vec<Vec<f64>>, Vec<usize>);

/// The `test` table as a standardized test set over the training's features, label column
/// and classes.
fn test_set(
    t: &Table,
    (names, label): (&[String], &str),
    classes: &[i64],
    (mean, scale): (&[f64], &[f64]),
) -> Result<TestSet, NodeError> {
    let mut tx = features(t, names).map_err(|e| NodeError::invalid("test", e.to_string()))?;
    let col = t
        .columns
        .iter()
        .position(|(n, _)| *n == label)
        .ok_or_else(|| NodeError::invalid("test", format!("no label column '{label}'")))?;
    let ty = int_labels(t, col).map_err(|e| NodeError::invalid("test", e.to_string()))?;
    let ty: Vec<usize> = ty
        .iter()
        .map(|&v| {
            classes.binary_search(&v).map_err(|_| {
                NodeError::invalid(
                    "test",
                    format!("label {v} is not among the training classes {classes:?}"),
                )
            })
        })
        .collect::<Result<_, _>>()?;
    dataset::apply_standardization(&mut tx, mean, scale);
    Ok((tx, ty))
}

/// The training parameters from the sockets, checked against the architecture.
fn train_params(ctx: &mut ExecContext, arch: Architecture) -> Result<TrainParams, NodeError> {
    let hidden: Vec<i64> = ctx.input("hidden")?;
    let hidden: Vec<usize> = hidden
        .iter()
        .map(|&h| usize::try_from(h).ok().filter(|h| (1..=4096).contains(h)))
        .collect::<Option<_>>()
        .ok_or_else(|| NodeError::invalid("hidden", "layer sizes must be between 1 and 4096"))?;
    let int = |name: &str, v: i64| {
        usize::try_from(v)
            .ok()
            .filter(|v| *v >= 1)
            .ok_or_else(|| NodeError::invalid(name, "must be at least 1"))
    };
    let lr: f64 = ctx.input("learning_rate")?;
    if !(lr.is_finite() && lr > 0.0) {
        return Err(NodeError::invalid("learning_rate", "must be positive"));
    }
    let p = TrainParams {
        hidden,
        activation: ctx.choice("activation")?,
        optimizer: ctx.choice("optimizer")?,
        learning_rate: lr,
        epochs: int("epochs", ctx.input("epochs")?)?,
        batch_size: int("batch_size", ctx.input("batch_size")?)?,
        seed: u64::try_from(ctx.input::<i64>("seed")?)
            .map_err(|_| NodeError::invalid("seed", "must be >= 0"))?,
    };
    if arch == Architecture::Rnn && p.hidden.len() != 1 {
        return Err(NodeError::invalid(
            "hidden",
            "an rnn has one hidden size (its state), e.g. [16]",
        ));
    }
    Ok(p)
}

/// The `log` output: one row per epoch, the training time in the metadata.
fn log_table(log: &[EpochLog], t0: std::time::Instant) -> Table {
    let mut table = Table::with_columns(&["epoch", "loss", "train_accuracy", "test_accuracy"]);
    for (e, l) in log.iter().enumerate() {
        table.push_row(&[(e + 1) as f64, l.loss, l.train_accuracy, l.test_accuracy]);
    }
    table.meta.insert(
        "train_seconds".into(),
        format!("{}", t0.elapsed().as_secs_f64()),
    );
    table
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let t0 = std::time::Instant::now();
    let tr: Arc<Table> = ctx.input("train")?;
    let te: Option<Arc<Table>> = ctx.input_opt("test")?;
    let key: String = ctx.input("label_column")?;
    let c =
        label_index(&tr, &key).map_err(|e| NodeError::invalid("label_column", e.to_string()))?;
    let label = tr.columns[c].0.clone();
    let (names, mut x, y) = labelled(&tr, c).map_err(LabelledError::into_node_error)?;
    let (classes, yi) = classes_of(&y)?;
    let standardize: bool = ctx.input("standardize")?;
    let (mean, scale) = if standardize {
        standardization(&x)
    } else {
        (vec![0.0; names.len()], vec![1.0; names.len()])
    };
    dataset::apply_standardization(&mut x, &mean, &scale);
    let test = match &te {
        None => None,
        Some(t) => Some(test_set(t, (&names, &label), &classes, (&mean, &scale))?),
    };
    let arch: Architecture = ctx.choice("model")?;
    let p = train_params(ctx, arch)?;
    let test = test.as_ref().map(|(a, b)| (a.as_slice(), b.as_slice()));
    let (net, log) = match arch {
        Architecture::Mlp => train(&x, &yi, classes.len(), test, &p),
        Architecture::Rnn => super::rnn::train(&x, &yi, classes.len(), test, &p),
    };
    if log.iter().any(|l| !l.loss.is_finite()) {
        return Err(NodeError::unstable(
            "the training loss is not finite: lower learning_rate",
        ));
    }
    let model = Model {
        kind: match arch {
            Architecture::Mlp => "mlp",
            Architecture::Rnn => "rnn",
        }
        .into(),
        activation: net.activation.name().into(),
        layers: net.layers,
        features: names,
        label,
        classes,
        mean,
        scale,
    };
    ctx.set_output("model", model);
    ctx.set_output("log", log_table(&log, t0));
    Ok(())
}

/// Registers `classifier_train`.
pub fn register(r: &mut Registry) {
    r.add("classifier_train", declare, execute);
}
