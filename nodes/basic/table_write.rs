//! `table_write`: writes a number, a list or a Table as CSV or JSON (by the path's extension).

use cgnodes_api::prelude::*;

fn declare(b: &mut NodeBuilder) {
    b.doc("Writes a scalar or a Table to CSV or JSON (chosen by the extension).");
    b.sink();
    b.add_input::<cgnodes_api::types::value_any::Any>("value")
        .doc("A number, a Table, or a list (numbers: column value; vec2: x, y; vec3: x, y, z; colours: r, g, b).");
    b.add_input::<String>("path")
        .file_out()
        .doc("Output file (.csv or .json), under the output directory.");
}

/// The value as a Table: a Table as is, a number as a one-cell table `value`, a list as
/// `list_table` lays it out.
pub fn as_table(v: &Value) -> Option<Table> {
    match v {
        Value::Table(t) => Some((**t).clone()),
        Value::Float(x) => Some(Table::from_row(&[("value", *x)])),
        Value::Int(x) => Some(Table::from_row(&[("value", *x as f64)])),
        Value::Bool(x) => Some(Table::from_row(&[("value", f64::from(u8::from(*x)))])),
        Value::List(items) => list_table(items),
        _ => None,
    }
}

/// A list as a table: numbers (and booleans) as one column `value`, `vec2` as columns `x`,
/// `y`, `vec3` as `x`, `y`, `z`, colours as `r`, `g`, `b`. An empty list is an empty
/// `value` column; a list mixing kinds or of other values has no table form.
fn list_table(items: &[Value]) -> Option<Table> {
    let (names, width): (&[&str], usize) = match items.first() {
        None | Some(Value::Float(_) | Value::Int(_) | Value::Bool(_)) => (&["value"], 1),
        Some(Value::Vec2(_)) => (&["x", "y"], 2),
        Some(Value::Vec3(_)) => (&["x", "y", "z"], 3),
        Some(Value::Color(_)) => (&["r", "g", "b"], 3),
        Some(_) => return None,
    };
    let mut cols = vec![Vec::with_capacity(items.len()); width];
    for it in items {
        let row: [f64; 3] = match (it, width) {
            (Value::Float(f), 1) => [*f, 0.0, 0.0],
            (Value::Int(i), 1) => [*i as f64, 0.0, 0.0],
            (Value::Bool(b), 1) => [f64::from(u8::from(*b)), 0.0, 0.0],
            (Value::Vec2(v), 2) => [v[0], v[1], 0.0],
            (Value::Vec3(v), 3) if names[0] == "x" => *v,
            (Value::Color(v), 3) if names[0] == "r" => *v,
            _ => return None,
        };
        for (c, v) in cols.iter_mut().zip(row) {
            c.push(v);
        }
    }
    Some(Table {
        columns: names.iter().map(|n| n.to_string()).zip(cols).collect(),
        ..Default::default()
    })
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_become_columns() {
        let t = as_table(&Value::from(vec![[1.0, 2.0], [3.0, 4.5]])).unwrap();
        assert_eq!(t.to_csv(), "x,y\n1,2\n3,4.5\n");
        let t = as_table(&Value::from(vec![1i64, 2])).unwrap();
        assert_eq!(t.column("value"), Some(&[1.0, 2.0][..]));
        let t = as_table(&Value::from(vec![[1.0, 2.0, 3.0]])).unwrap();
        assert_eq!(t.column("z"), Some(&[3.0][..]));
        // Mixed kinds have no table form.
        let mixed = Value::List(Arc::new(vec![Value::Float(1.0), Value::Vec2([1.0, 2.0])]));
        assert!(as_table(&mixed).is_none());
        assert!(as_table(&Value::from("text")).is_none());
    }
}
