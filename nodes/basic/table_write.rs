//! `table_write`: writes a number or a Table as CSV or JSON (by the path's extension).

use crate::prelude::*;

fn declare(b: &mut NodeBuilder) {
    b.doc("Writes a scalar or a Table to CSV or JSON (chosen by the extension).");
    b.sink();
    b.add_input::<crate::types::value_any::Any>("value")
        .doc("A number, a list of numbers, or a Table.");
    b.add_input::<String>("path")
        .file_out()
        .doc("Output file (.csv or .json), under the output directory.");
}

/// The value as a Table: a Table as is, a number as a one-cell table `value`.
pub fn as_table(v: &Value) -> Option<Table> {
    match v {
        Value::Table(t) => Some((**t).clone()),
        Value::Float(x) => Some(Table::from_row(&[("value", *x)])),
        Value::Int(x) => Some(Table::from_row(&[("value", *x as f64)])),
        Value::Bool(x) => Some(Table::from_row(&[("value", f64::from(u8::from(*x)))])),
        Value::List(items) => {
            let col: Option<Vec<f64>> = items
                .iter()
                .map(|x| match x {
                    Value::Float(f) => Some(*f),
                    Value::Int(i) => Some(*i as f64),
                    _ => None,
                })
                .collect();
            Some(Table {
                columns: vec![("value".into(), col?)],
                ..Default::default()
            })
        }
        _ => None,
    }
}

/// JSON text of a table: `{"columns": {name: [values]}, "meta": {...}}`.
pub fn table_json(t: &Table) -> String {
    let cols: serde_json::Map<String, serde_json::Value> = t
        .columns
        .iter()
        .map(|(n, c)| (n.clone(), serde_json::json!(c)))
        .collect();
    let j = serde_json::json!({"columns": cols, "meta": t.meta});
    serde_json::to_string_pretty(&j).unwrap_or_default()
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let v = ctx
        .input_value("value")
        .cloned()
        .ok_or_else(|| NodeError::invalid("value", "no value"))?;
    let table = as_table(&v).ok_or_else(|| {
        NodeError::invalid(
            "value",
            format!("a {} cannot be written as a table", v.socket_type()),
        )
    })?;
    let p: String = ctx.input("path")?;
    let path = ctx.output_path("path", &p)?;
    let text = match path.extension().and_then(|e| e.to_str()) {
        Some("csv") => table.to_csv(),
        Some("json") => table_json(&table),
        _ => {
            return Err(NodeError::invalid(
                "path",
                format!("'{p}' should end in .csv or .json"),
            ))
        }
    };
    ctx.write_file(&path, text.as_bytes())
}

/// Registers `table_write`.
pub fn register(r: &mut Registry) {
    r.add("table_write", declare, execute);
}
