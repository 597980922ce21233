//! `points_load`: 2-D points (and optional integer labels) from two (three) columns of a
//! file or a table: the course's `x y` curve files and `x y label` insect files.

use super::table_load::{load_table_file, Header};
use cgnodes_api::prelude::*;

/// Why a column cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ColumnError {
    /// The index is past the last column.
    #[error("no column {index}: the table has {count} columns ({names})")]
    NoIndex {
        /// The 0-based index asked for.
        index: usize,
        /// Number of columns.
        count: usize,
        /// The column names, comma-separated.
        names: String,
    },
    /// No column has this name.
    #[error("no column '{key}' (columns: {names})")]
    NoName {
        /// The name asked for.
        key: String,
        /// The column names, comma-separated.
        names: String,
    },
    /// A label is not an integer (row 0-based).
    #[error("row {row}: label {value} is not an integer")]
    NotInteger {
        /// The row.
        row: usize,
        /// Its value.
        value: f64,
    },
}

/// Finds a column by header name, else by 0-based index (`"2"`).
pub fn find_column<'t>(t: &'t Table, key: &str) -> Result<&'t [f64], ColumnError> {
    if let Some(c) = t.column(key) {
        return Ok(c);
    }
    let names = || {
        t.columns
            .iter()
            .map(|(n, _)| n.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    match key.trim().parse::<usize>() {
        Ok(i) => t
            .columns
            .get(i)
            .map(|(_, c)| c.as_slice())
            .ok_or_else(|| ColumnError::NoIndex {
                index: i,
                count: t.columns.len(),
                names: names(),
            }),
        Err(_) => Err(ColumnError::NoName {
            key: key.to_string(),
            names: names(),
        }),
    }
}

/// Values of a label column as integers; a non-integer value is an error naming its row
/// (0-based).
pub fn integer_labels(col: &[f64]) -> Result<Vec<i64>, ColumnError> {
    col.iter()
        .enumerate()
        .map(|(i, &v)| {
            if v.fract() == 0.0 && v.abs() < 9e15 {
                Ok(v as i64)
            } else {
                Err(ColumnError::NotInteger { row: i, value: v })
            }
        })
        .collect()
}

/// Points from columns `x` and `y` of `t`, with labels from column `label` when given.
pub fn table_points(t: &Table, x: &str, y: &str) -> Result<Vec<[f64; 2]>, (&'static str, String)> {
    let xs = find_column(t, x).map_err(|e| ("x_column", e.to_string()))?;
    let ys = find_column(t, y).map_err(|e| ("y_column", e.to_string()))?;
    if xs.len() != ys.len() {
        return Err(("y_column", "the x and y columns differ in length".into()));
    }
    if let Some(i) = xs
        .iter()
        .zip(ys)
        .position(|(a, b)| !(a.is_finite() && b.is_finite()))
    {
        return Err(("x_column", format!("row {i} is not finite")));
    }
    Ok(xs.iter().zip(ys).map(|(&a, &b)| [a, b]).collect())
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Reads 2-D points (and integer labels) from columns of a file or a table.");
    b.add_input::<String>("path")
        .optional()
        .file_in()
        .doc("A CSV or whitespace-separated file (header optional); or connect table.");
    b.add_input::<Table>("table")
        .optional()
        .doc("A table instead of a file.");
    b.add_input::<String>("x_column")
        .default("0")
        .doc("Column of x: a header name or a 0-based index.");
    b.add_input::<String>("y_column")
        .default("1")
        .doc("Column of y: a header name or a 0-based index.");
    b.add_input::<String>("label_column").default("auto").doc(
        "Column of integer labels: a name or index; auto = the third column if there is one; none.",
    );
    b.add_output::<Vec<[f64; 2]>>("points");
    b.add_output::<Vec<i64>>("labels")
        .doc("One integer label per point (empty without a label column).");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let p: Option<String> = ctx.input_opt("path")?;
    let t: Option<Arc<Table>> = ctx.input_opt("table")?;
    let table = match (p, t) {
        (Some(_), Some(_)) => {
            return Err(NodeError::invalid(
                "path",
                "give either path or table, not both",
            ))
        }
        (Some(p), None) => Arc::new(load_table_file(ctx, "path", &p, Header::Auto)?),
        (None, Some(t)) => t,
        (None, None) => {
            return Err(NodeError::invalid(
                "path",
                "no data: give path or connect table",
            ))
        }
    };
    let x: String = ctx.input("x_column")?;
    let y: String = ctx.input("y_column")?;
    let points = table_points(&table, &x, &y).map_err(|(s, e)| NodeError::invalid(s, e))?;
    let lc: String = ctx.input("label_column")?;
    let labels = match lc.as_str() {
        "none" => Vec::new(),
        "auto" if table.columns.len() < 3 => Vec::new(),
        key => {
            let key = if key == "auto" { "2" } else { key };
            let col = find_column(&table, key)
                .map_err(|e| NodeError::invalid("label_column", e.to_string()))?;
            integer_labels(col).map_err(|e| NodeError::invalid("label_column", e.to_string()))?
        }
    };
    ctx.set_output("points", points);
    ctx.set_output("labels", labels);
    Ok(())
}

/// Registers `points_load`.
pub fn register(r: &mut Registry) {
    r.add("points_load", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::super::table_load::parse_table;
    use super::*;

    #[test]
    fn columns_by_name_or_index_and_labels() {
        let t = parse_table("a b lab\n1 2 0\n3 4 1\n", Header::Auto).unwrap();
        assert_eq!(
            table_points(&t, "a", "1").unwrap(),
            vec![[1.0, 2.0], [3.0, 4.0]]
        );
        assert_eq!(
            integer_labels(find_column(&t, "lab").unwrap()).unwrap(),
            vec![0, 1]
        );
        let e = table_points(&t, "0", "7").unwrap_err();
        assert_eq!(e.0, "y_column");
        assert!(e.1.contains("no column 7"), "{}", e.1);
        assert!(integer_labels(&[1.0, 2.5])
            .unwrap_err()
            .to_string()
            .contains("row 1"));
    }
}
