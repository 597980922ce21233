//! Tables as classification data: feature columns, an integer label column, the
//! standardization, and the conversion between the `Model` socket value and a network.

use super::mlp::{Activation, Mlp};
use cgnodes_api::node::Choice;
use cgnodes_api::types::{Model, Table};

/// Features and labels read from a table.
#[derive(Clone, Debug, PartialEq)]
pub struct Dataset {
    /// One feature vector per row.
    pub x: Vec<Vec<f64>>,
    /// One label per row (absent when the table has no label column).
    pub labels: Option<Vec<i64>>,
}

/// The index of the label column: a header name, a 0-based index, or the last column for "".
pub fn label_index(t: &Table, key: &str) -> Result<usize, String> {
    if t.columns.is_empty() {
        return Err("the table has no columns".into());
    }
    if key.is_empty() {
        return Ok(t.columns.len() - 1);
    }
    if let Some(i) = t.columns.iter().position(|(n, _)| n == key) {
        return Ok(i);
    }
    match key.parse::<usize>() {
        Ok(i) if i < t.columns.len() => Ok(i),
        _ => Err(format!(
            "no column '{key}' (columns: {})",
            t.columns
                .iter()
                .map(|(n, _)| n.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )),
    }
}

/// The values of column `c` as integer labels.
pub fn int_labels(t: &Table, c: usize) -> Result<Vec<i64>, String> {
    let (name, col) = &t.columns[c];
    col.iter()
        .enumerate()
        .map(|(r, &v)| {
            if v.is_finite() && v.fract() == 0.0 && v.abs() < 9e15 {
                Ok(v as i64)
            } else {
                Err(format!(
                    "column '{name}' row {r}: {v} is not an integer label"
                ))
            }
        })
        .collect()
}

/// Rows of the columns `names` (in that order) as feature vectors; every value finite.
pub fn features(t: &Table, names: &[String]) -> Result<Vec<Vec<f64>>, String> {
    let cols: Vec<&[f64]> = names
        .iter()
        .map(|n| {
            t.column(n)
                .ok_or_else(|| format!("no feature column '{n}'"))
        })
        .collect::<Result<_, _>>()?;
    let rows = cols.first().map_or(0, |c| c.len());
    (0..rows)
        .map(|r| {
            cols.iter()
                .zip(names)
                .map(|(c, n)| {
                    c.get(r)
                        .copied()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| format!("column '{n}' row {r} is missing or not finite"))
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
pub fn network(m: &Model) -> Result<Mlp, String> {
    let activation = Activation::from_name(&m.activation)
        .ok_or_else(|| format!("unknown activation '{}'", m.activation))?;
    let n_f = m.features.len();
    if m.layers.is_empty() || m.mean.len() != n_f || m.scale.len() != n_f {
        return Err("the model's layers or standardization do not fit its features".into());
    }
    let mut n = match m.kind.as_str() {
        "mlp" => n_f,
        "rnn" => {
            let h = m.layers[0].outputs;
            if m.layers.len() != 2 || m.layers[0].inputs != 1 + h {
                return Err(
                    "an rnn has a cell of 1 + h inputs and h outputs, then one output layer".into(),
                );
            }
            1 + h
        }
        other => return Err(format!("unknown model kind '{other}'")),
    };
    for (i, l) in m.layers.iter().enumerate() {
        if l.inputs != n || l.weights.len() != l.inputs * l.outputs || l.bias.len() != l.outputs {
            return Err(format!("layer {i} has inconsistent sizes"));
        }
        n = l.outputs;
    }
    if n != m.classes.len() {
        return Err("the last layer's size differs from the number of classes".into());
    }
    Ok(Mlp {
        layers: m.layers.clone(),
        activation,
    })
}

/// The class values the model predicts for raw (unstandardized) rows.
pub fn predict(m: &Model, x: &[Vec<f64>]) -> Result<Vec<i64>, String> {
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
