//! `table_slice`: a range of rows of a table (for example the insect test set's first 60
//! rows, which the training set also holds, and the 150 after them).

use cgnodes_api::prelude::*;

/// Rows `start .. start + count` of `t` (fewer at the end of the table).
pub fn slice_rows(t: &Table, start: usize, count: usize) -> Table {
    Table {
        columns: t
            .columns
            .iter()
            .map(|(n, c)| {
                let a = start.min(c.len());
                let b = start.saturating_add(count).min(c.len());
                (n.clone(), c[a..b].to_vec())
            })
            .collect(),
        meta: t.meta.clone(),
    }
}

fn declare(b: &mut NodeBuilder) {
    b.doc("A range of rows of a table.");
    b.add_input::<Table>("table");
    b.add_input::<i64>("start")
        .default(0)
        .min(0.0)
        .doc("First row (0-based).");
    b.add_input::<i64>("count")
        .default(-1)
        .doc("Number of rows; -1 = to the end.");
    b.add_output::<Table>("table");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let t: Arc<Table> = ctx.input("table")?;
    let start = usize::try_from(ctx.input::<i64>("start")?)
        .map_err(|_| NodeError::invalid("start", "must be >= 0"))?;
    let count: i64 = ctx.input("count")?;
    let count = if count < 0 {
        usize::MAX
    } else {
        count as usize
    };
    if start >= t.num_rows() {
        return Err(NodeError::invalid(
            "start",
            format!("the table has {} rows", t.num_rows()),
        ));
    }
    ctx.set_output("table", slice_rows(&t, start, count));
    Ok(())
}

/// Registers `table_slice`.
pub fn register(r: &mut Registry) {
    r.add("table_slice", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slices_every_column() {
        let t = Table {
            columns: vec![
                ("a".into(), vec![1.0, 2.0, 3.0]),
                ("b".into(), vec![4.0, 5.0, 6.0]),
            ],
            ..Default::default()
        };
        let s = slice_rows(&t, 1, 5);
        assert_eq!(s.column("a"), Some(&[2.0, 3.0][..]));
        assert_eq!(s.column("b"), Some(&[5.0, 6.0][..]));
    }
}
