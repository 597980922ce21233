//! Tables as classification data: feature columns, an integer label column, the
//! standardization, and the conversion between the `Model` socket value and a network.

use super::mlp::{Activation, Mlp};
use cgnodes_api::node::Choice;
use cgnodes_api::types::{Model, Table};

/// A table that cannot be read as classification data: the column and row at fault.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TableError {
    /// The table has no column at all.
    #[error("the table has no columns")]
    NoColumns,
    /// The requested label column is neither a header name nor an index.
    #[error("no column '{key}' (columns: {columns})")]
    NoColumn {
        /// The name or index asked for.
        key: String,
        /// The table's column names, comma-separated.
        columns: String,
    },
    /// A label is not an integer.
    #[error("column '{column}' row {row}: {value} is not an integer label")]
    NotInteger {
        /// The label column.
        column: String,
        /// The 0-based row.
        row: usize,
        /// The value found.
        value: f64,
    },
    /// A feature column named by the model or the caller is missing.
    #[error("no feature column '{0}'")]
    NoFeature(String),
    /// A feature value is missing or NaN/infinite.
    #[error("column '{column}' row {row} is missing or not finite")]
    NotFinite {
        /// The feature column.
        column: String,
        /// The 0-based row.
        row: usize,
    },
}

/// A `Model` value whose network cannot be rebuilt: the field at fault.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// The activation name is not one of `Activation`'s.
    #[error("unknown activation '{0}'")]
    Activation(String),
    /// No layers, or the mean/scale vectors differ from the feature count.
    #[error("the model's layers or standardization do not fit its features")]
    Standardization,
    /// An `rnn` model whose layers are not a cell and an output layer.
    #[error("an rnn has a cell of 1 + h inputs and h outputs, then one output layer")]
    RnnShape,
    /// The kind is neither `mlp` nor `rnn`.
    #[error("unknown model kind '{0}'")]
    Kind(String),
    /// Layer `0`'s weight or bias sizes do not chain.
    #[error("layer {0} has inconsistent sizes")]
    LayerSizes(usize),
    /// The output layer's size differs from the class list.
    #[error("the last layer's size differs from the number of classes")]
    Classes,
}

/// Features and labels read from a table.
#[derive(Clone, Debug, PartialEq)]
pub struct Dataset {
    /// One feature vector per row.
    pub x: Vec<Vec<f64>>,
    /// One label per row (absent when the table has no label column).
    pub labels: Option<Vec<i64>>,
}

/// The index of the label column: a header name, a 0-based index, or the last column for "".
pub fn label_index(t: &Table, key: &str) -> Result<usize, TableError> {
    if t.columns.is_empty() {
        return Err(TableError::NoColumns);
    }
    if key.is_empty() {
        return Ok(t.columns.len() - 1);
    }
    if let Some(i) = t.columns.iter().position(|(n, _)| n == key) {
        return Ok(i);
    }
    match key.parse::<usize>() {
        Ok(i) if i < t.columns.len() => Ok(i),
        _ => Err(TableError::NoColumn {
            key: key.to_string(),
            columns: t
                .columns
                .iter()
                .map(|(n, _)| n.as_str())
                .collect::<Vec<_>>()
                .join(", "),
        }),
    }
}

/// The values of column `c` as integer labels.
pub fn int_labels(t: &Table, c: usize) -> Result<Vec<i64>, TableError> {
    let (name, col) = &t.columns[c];
    col.iter()
        .enumerate()
        .map(|(r, &v)| {
            if v.is_finite() && v.fract() == 0.0 && v.abs() < 9e15 {
                Ok(v as i64)
            } else {
                Err(TableError::NotInteger {
                    column: name.clone(),
                    row: r,
                    value: v,
                })
            }
        })
        .collect()
}

/// Rows of the columns `names` (in that order) as feature vectors; every value finite.
pub fn features(t: &Table, names: &[String]) -> Result<Vec<Vec<f64>>, TableError> {
    let cols: Vec<&[f64]> = names
        .iter()
        .map(|n| t.column(n).ok_or_else(|| TableError::NoFeature(n.clone())))
        .collect::<Result<_, _>>()?;
    let rows = cols.first().map_or(0, |c| c.len());
    (0..rows)
        .map(|r| {
            cols.iter()
                .zip(names)
                .map(|(c, n)| {
                    c.get(r).copied().filter(|v| v.is_finite()).ok_or_else(|| {
                        TableError::NotFinite {
                            column: n.clone(),
                            row: r,
                        }
                    })
                })
                .collect()
        })
        .collect()
}

/// Per-feature mean and standard deviation (1 where a feature is constant).
pub fn standardization(x: &[Vec<f64>]) -> (Vec<f64>, Vec<f64>) {
    let d = x.first().map_or(0, Vec::len);
    let n = x.len().max(1) as f64;
    let mean: Vec<f64> = (0..d)
        .map(|k| x.iter().map(|r| r[k]).sum::<f64>() / n)
        .collect();
    let scale = (0..d)
        .map(|k| {
            let s = (x.iter().map(|r| (r[k] - mean[k]).powi(2)).sum::<f64>() / n).sqrt();
            if s > 0.0 {
                s
            } else {
                1.0
            }
        })
        .collect();
    (mean, scale)
}

/// `x` standardized in place.
pub fn apply_standardization(x: &mut [Vec<f64>], mean: &[f64], scale: &[f64]) {
    for r in x {
        for ((v, m), s) in r.iter_mut().zip(mean).zip(scale) {
            *v = (*v - m) / s;
        }
    }
}

/// The network of a model value, checked for consistent sizes (an `rnn` is stored as its
/// cell [W_x | W_h] and output layers, `rnn.rs`).
pub fn network(m: &Model) -> Result<Mlp, ModelError> {
    let activation = Activation::from_name(&m.activation)
        .ok_or_else(|| ModelError::Activation(m.activation.clone()))?;
    let n_f = m.features.len();
    if m.layers.is_empty() || m.mean.len() != n_f || m.scale.len() != n_f {
        return Err(ModelError::Standardization);
    }
    let mut n = match m.kind.as_str() {
        "mlp" => n_f,
        "rnn" => {
            let h = m.layers[0].outputs;
            if m.layers.len() != 2 || m.layers[0].inputs != 1 + h {
                return Err(ModelError::RnnShape);
            }
            1 + h
        }
        other => return Err(ModelError::Kind(other.to_string())),
    };
    for (i, l) in m.layers.iter().enumerate() {
        if l.inputs != n || l.weights.len() != l.inputs * l.outputs || l.bias.len() != l.outputs {
            return Err(ModelError::LayerSizes(i));
        }
        n = l.outputs;
    }
    if n != m.classes.len() {
        return Err(ModelError::Classes);
    }
    Ok(Mlp {
        layers: m.layers.clone(),
        activation,
    })
}

/// The class values the model predicts for raw (unstandardized) rows.
pub fn predict(m: &Model, x: &[Vec<f64>]) -> Result<Vec<i64>, ModelError> {
    let net = network(m)?;
    let mut x = x.to_vec();
    apply_standardization(&mut x, &m.mean, &m.scale);
    let rnn = m.kind == "rnn";
    Ok(x.iter()
        .map(|r| {
            let k = if rnn {
                super::rnn::predict(&net, r)
            } else {
                net.predict(r)
            };
            m.classes[k]
        })
        .collect())
}
