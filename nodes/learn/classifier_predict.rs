//! `classifier_predict`: the labels a trained model gives the rows of a table, with the
//! accuracy and the confusion matrix when the table has the model's label column.

use super::dataset::{features, int_labels, predict};
use cgnodes_api::prelude::*;

fn declare(b: &mut NodeBuilder) {
    b.doc("Classifies the rows of a table with a trained model; accuracy and confusion matrix when labels are present.");
    b.add_input::<Model>("model");
    b.add_input::<Table>("data")
        .doc("Rows with the model's feature columns (and optionally its label column).");
    b.add_output::<Vec<i64>>("labels")
        .doc("The predicted label of every row.");
    b.add_output::<Table>("table")
        .doc("One row: rows, correct, accuracy (NaN without a label column).");
    b.add_output::<Table>("confusion")
        .doc("Row per true class: class, then predicted_<c> counts per predicted class.");
}

/// Accuracy and confusion matrix (rows: true class, columns: predicted) over `classes`.
pub fn confusion(classes: &[i64], truth: &[i64], pred: &[i64]) -> (f64, Vec<Vec<usize>>) {
    let k = classes.len();
    let mut m = vec![vec![0usize; k]; k];
    let idx = |v: i64| classes.iter().position(|c| *c == v);
    let mut ok = 0;
    for (t, p) in truth.iter().zip(pred) {
        if t == p {
            ok += 1;
        }
        if let (Some(a), Some(b)) = (idx(*t), idx(*p)) {
            m[a][b] += 1;
        }
    }
    (ok as f64 / truth.len().max(1) as f64, m)
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let m: Arc<Model> = ctx.input("model")?;
    let t: Arc<Table> = ctx.input("data")?;
    let x = features(&t, &m.features).map_err(|e| NodeError::invalid("data", e.to_string()))?;
    let pred = predict(&m, &x).map_err(|e| NodeError::invalid("model", e.to_string()))?;
    let truth = match t.columns.iter().position(|(n, _)| *n == m.label) {
        Some(c) => Some(int_labels(&t, c).map_err(|e| NodeError::invalid("data", e.to_string()))?),
        None => None,
    };
    let mut cols: Vec<&str> = vec!["class"];
    let names: Vec<String> = m.classes.iter().map(|c| format!("predicted_{c}")).collect();
    cols.extend(names.iter().map(String::as_str));
    let mut conf = Table::with_columns(&cols);
    let (acc, correct) = match &truth {
        Some(tr) => {
            let (acc, mat) = confusion(&m.classes, tr, &pred);
            for (c, row) in m.classes.iter().zip(&mat) {
                let mut r = vec![*c as f64];
                r.extend(row.iter().map(|&v| v as f64));
                conf.push_row(&r);
            }
            (
                acc,
                tr.iter().zip(&pred).filter(|(a, b)| a == b).count() as f64,
            )
        }
        None => (f64::NAN, f64::NAN),
    };
    ctx.set_output(
        "table",
        Table::from_row(&[
            ("rows", pred.len() as f64),
            ("correct", correct),
            ("accuracy", acc),
        ]),
    );
    ctx.set_output("confusion", conf);
    ctx.set_output("labels", pred);
    Ok(())
}

/// Registers `classifier_predict`.
pub fn register(r: &mut Registry) {
    r.add("classifier_predict", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn confusion_counts_by_true_and_predicted_class() {
        let (acc, m) = confusion(&[0, 1, 2], &[0, 0, 1, 2, 2], &[0, 1, 1, 2, 0]);
        assert!((acc - 0.6).abs() < 1e-15);
        assert_eq!(m, vec![vec![1, 1, 0], vec![0, 1, 0], vec![1, 0, 1]]);
    }
}
