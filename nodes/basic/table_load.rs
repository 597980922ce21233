//! `table_load`: reads a table of numbers from a CSV or whitespace-separated text file, with
//! or without a header row (the course's data files are `x y` or `x y label` per line).

use cgnodes_api::prelude::*;
use std::path::Path;

/// Whether the first row names the columns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Header {
    /// A header when the first row is not all numbers.
    Auto,
    /// The first row is a header.
    Yes,
    /// Every row is data.
    No,
}

impl Choice for Header {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("auto", Header::Auto),
        ("yes", Header::Yes),
        ("no", Header::No),
    ];
}

/// Why text is not a table of numbers.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TableError {
    /// The CSV reader's own error.
    #[error("{0}")]
    Csv(String),
    /// No data or header row.
    #[error("the file has no rows")]
    NoRows,
    /// The first row is empty.
    #[error("the first row has no fields")]
    NoFields,
    /// A row's field count differs from the first row's (rows counted from 1 over
    /// non-blank, non-comment lines, header included).
    #[error("row {line} has {fields} fields, the first row {expected}")]
    RowLength {
        /// The row.
        line: usize,
        /// Its field count.
        fields: usize,
        /// The first row's field count.
        expected: usize,
    },
    /// A field is not a finite number.
    #[error("row {line}, column {column}: '{field}' is not a finite number")]
    NotANumber {
        /// The row.
        line: usize,
        /// The column index.
        column: usize,
        /// The field's text.
        field: String,
    },
}

/// The name given to column `i` of a file without a header: `c0`, `c1`, ...
pub fn default_column_name(i: usize) -> String {
    format!("c{i}")
}

/// Splits `text` into rows of fields: CSV (through `cgnodes_api::io::csv`) when the first data line
/// has a comma, else fields separated by spaces or tabs. Blank lines and `#` comments are
/// skipped, fields trimmed.
fn split_rows(text: &str) -> Result<Vec<Vec<String>>, TableError> {
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'));
    let Some(first) = first else {
        return Ok(Vec::new());
    };
    if first.contains(',') {
        let rows = cgnodes_api::io::csv::read(text, true, true).map_err(TableError::Csv)?;
        Ok(rows
            .map(|r| std::iter::once(r.header).chain(r.rows).collect())
            .unwrap_or_default())
    } else {
        Ok(text
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !l.starts_with('#'))
            .map(|l| l.split_whitespace().map(String::from).collect())
            .collect())
    }
}

/// Parses a table of numbers. Every data row must have as many fields as the first row (or
/// the header), every field must be a finite number. Without a header the columns are named
/// `c0`, `c1`, ... (`default_column_name`).
pub fn parse_table(text: &str, header: Header) -> Result<Table, TableError> {
    let rows = split_rows(text)?;
    let Some(first) = rows.first() else {
        return Err(TableError::NoRows);
    };
    let numeric = |s: &str| s.parse::<f64>().is_ok();
    let has_header = match header {
        Header::Yes => true,
        Header::No => false,
        Header::Auto => !first.iter().all(|f| numeric(f)),
    };
    let names: Vec<String> = if has_header {
        first.clone()
    } else {
        (0..first.len()).map(default_column_name).collect()
    };
    if names.is_empty() {
        return Err(TableError::NoFields);
    }
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
    let data = &rows[usize::from(has_header)..];
    for (r, row) in data.iter().enumerate() {
        // Rows are counted from 1 over non-blank, non-comment lines, header included.
        let line = r + 1 + usize::from(has_header);
        if row.len() != names.len() {
            return Err(TableError::RowLength {
                line,
                fields: row.len(),
                expected: names.len(),
            });
        }
        for (c, (col, s)) in cols.iter_mut().zip(row).enumerate() {
            let v: f64 = s
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite())
                .ok_or_else(|| TableError::NotANumber {
                    line,
                    column: c,
                    field: s.clone(),
                })?;
            col.push(v);
        }
    }
    Ok(Table {
        columns: names.into_iter().zip(cols).collect(),
        ..Default::default()
    })
}

/// Reads and parses the file behind socket `socket` (`path`), quoting the file's content in
/// errors only when the file lies inside the run's folders (issue 23).
pub fn load_table_file(
    ctx: &ExecContext,
    socket: &str,
    p: &str,
    header: Header,
) -> Result<Table, NodeError> {
    let path = ctx.input_path(p);
    let text = std::fs::read_to_string(&path).map_err(|e| NodeError::io(&path, e).at(socket))?;
    parse_table(&text, header).map_err(|e| {
        let e = if ctx.files().is_within_run_folders(&path) {
            e.to_string()
        } else {
            "not a table of numbers (CSV or whitespace-separated)".into()
        };
        NodeError::invalid(socket, format!("{}: {e}", Path::new(p).display()))
    })
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Reads a table of numbers: CSV or whitespace-separated text, header optional.");
    b.add_input::<String>("path")
        .file_in()
        .doc("The file (.csv, .txt, ...); blank lines and # comments are skipped.");
    b.add_choice::<Header>("header")
        .doc("auto: the first row is a header when it is not all numbers; yes; no (columns c0, c1, ...).");
    b.add_output::<Table>("table");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let p: String = ctx.input("path")?;
    let header: Header = ctx.choice("header")?;
    let t = load_table_file(ctx, "path", &p, header)?;
    ctx.set_output("table", t);
    Ok(())
}

/// Registers `table_load`.
pub fn register(r: &mut Registry) {
    r.add("table_load", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_whitespace_and_csv_with_or_without_header() {
        let t = parse_table("# insects\n1.5 2\t3\n\n4 5 6\n", Header::Auto).unwrap();
        assert_eq!(t.column("c0"), Some(&[1.5, 4.0][..]));
        assert_eq!(t.column("c2"), Some(&[3.0, 6.0][..]));
        let t = parse_table("x, y\n1, 2\n3, -4e-1\n", Header::Auto).unwrap();
        assert_eq!(t.column("y"), Some(&[2.0, -0.4][..]));
        let t = parse_table("1,2\n3,4\n", Header::Yes).unwrap();
        assert_eq!(t.column("1"), Some(&[3.0][..]));
    }

    #[test]
    fn bad_rows_are_named() {
        let e = parse_table("1 2\n3\n", Header::Auto)
            .unwrap_err()
            .to_string();
        assert!(e.contains("row 2 has 1 fields"), "{e}");
        let e = parse_table("x y\n1 nan\n", Header::Auto)
            .unwrap_err()
            .to_string();
        assert!(e.contains("row 2, column 1: 'nan'"), "{e}");
        assert!(parse_table("x y\n1 b\n", Header::No).is_err());
        assert!(parse_table("\n# only\n", Header::Auto).is_err());
    }
}
