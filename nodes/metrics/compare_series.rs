//! `compare_series`: a simulated series against a reference series from a CSV file (for
//! example a dam-break surge front against Martin & Moyce's measurements), as the RMS
//! relative error, with an optional anchor that shifts the simulated x (time) so both pass
//! through one chosen point.

use cgnodes_api::prelude::*;
use std::path::Path;

/// Why a series could not be read or compared.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SeriesError {
    /// The CSV reader's own error.
    #[error("{0}")]
    Csv(String),
    /// The text holds no rows at all.
    #[error("empty CSV")]
    EmptyCsv,
    /// The header has no column of this name.
    #[error("no column '{name}' (columns: {columns})")]
    NoColumn {
        /// The column asked for.
        name: String,
        /// The header's columns, comma-separated.
        columns: String,
    },
    /// A field of a row (numbered from 1 with the header) is missing, not a number or not
    /// finite.
    #[error("row {0}: bad number")]
    BadNumber(usize),
    /// Fewer than two finite simulated points.
    #[error("the simulated series has fewer than two points")]
    TooFewPoints,
    /// The simulation never reaches the anchor's y.
    #[error("the simulated series never reaches the anchor y = {0}")]
    AnchorNotReached(f64),
    /// No counted reference point lies within the simulated range.
    #[error("no reference point falls inside the simulated series")]
    NoOverlap,
}

/// Reads two named numeric columns from CSV text with a header row (blank lines and lines
/// starting with `#` are skipped, fields trimmed).
pub fn read_csv_columns(text: &str, x: &str, y: &str) -> Result<Vec<(f64, f64)>, SeriesError> {
    let csv = cgnodes_api::io::csv::read(text, true, true)
        .map_err(SeriesError::Csv)?
        .ok_or(SeriesError::EmptyCsv)?;
    let col = |name: &str| {
        csv.column(name).ok_or_else(|| SeriesError::NoColumn {
            name: name.to_string(),
            columns: csv.header.join(", "),
        })
    };
    let (ix, iy) = (col(x)?, col(y)?);
    let mut out = Vec::new();
    for (k, f) in csv.rows.iter().enumerate() {
        let num = |i: usize| {
            f.get(i)
                .and_then(|s| s.parse::<f64>().ok())
                .filter(|v| v.is_finite())
                .ok_or(SeriesError::BadNumber(k + 2))
        };
        out.push((num(ix)?, num(iy)?));
    }
    Ok(out)
}

/// Linear interpolation of y at `x` over points sorted by x; `None` outside the range.
fn y_at(s: &[(f64, f64)], x: f64) -> Option<f64> {
    let k = s.windows(2).position(|w| w[0].0 <= x && x <= w[1].0)?;
    let (a, b) = (s[k], s[k + 1]);
    Some(if b.0 > a.0 {
        a.1 + (b.1 - a.1) * (x - a.0) / (b.0 - a.0)
    } else {
        a.1
    })
}

/// The first x at which y reaches `y` (linear between samples); `None` if it never does.
fn first_x_reaching(s: &[(f64, f64)], y: f64) -> Option<f64> {
    if s.first()?.1 >= y {
        return Some(s[0].0);
    }
    s.windows(2).find(|w| w[0].1 < y && w[1].1 >= y).map(|w| {
        let (a, b) = (w[0], w[1]);
        a.0 + (b.0 - a.0) * (y - a.1) / (b.1 - a.1)
    })
}

/// Per-point comparison: (x_ref, y_ref, simulated value, relative error).
pub type Comparison = Vec<(f64, f64, f64, f64)>;

/// Compares `sim` to `reference`. With `error_in_x`, the error of each reference point is in
/// the x at which the simulation first reaches its y (as for a surge front's arrival time);
/// otherwise in y at its x. `anchor` = (x, y) shifts the simulation in x so that it reaches
/// y at x. Only reference points with y >= `min_y` count. Returns the RMS relative error and
/// the per-point table.
pub fn compare_series(
    sim: &[(f64, f64)],
    reference: &[(f64, f64)],
    error_in_x: bool,
    anchor: Option<(f64, f64)>,
    min_y: f64,
) -> Result<(f64, Comparison), SeriesError> {
    let mut s: Vec<(f64, f64)> = sim
        .iter()
        .copied()
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    s.sort_by(|a, b| a.0.total_cmp(&b.0));
    if s.len() < 2 {
        return Err(SeriesError::TooFewPoints);
    }
    if let Some((ax, ay)) = anchor {
        let sx = first_x_reaching(&s, ay).ok_or(SeriesError::AnchorNotReached(ay))?;
        let dx = ax - sx;
        for p in &mut s {
            p.0 += dx;
        }
    }
    let mut rows = Vec::new();
    for &(xr, yr) in reference.iter().filter(|p| p.1 >= min_y) {
        let (sim_v, err) = if error_in_x {
            match first_x_reaching(&s, yr) {
                Some(xs) => (xs, (xs - xr) / xr),
                None => continue,
            }
        } else {
            match y_at(&s, xr) {
                Some(ys) => (ys, (ys - yr) / yr),
                None => continue,
            }
        };
        if err.is_finite() {
            rows.push((xr, yr, sim_v, err));
        }
    }
    if rows.is_empty() {
        return Err(SeriesError::NoOverlap);
    }
    let rms = (rows.iter().map(|r| r.3 * r.3).sum::<f64>() / rows.len() as f64).sqrt();
    Ok((rms, rows))
}

/// The axis the error is measured along (the `error_in` socket).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ErrorIn {
    /// The arrival x of each reference y.
    X,
    /// The y at each reference x.
    Y,
}

impl Choice for ErrorIn {
    const CHOICES: &'static [(&'static str, Self)] = &[("x", ErrorIn::X), ("y", ErrorIn::Y)];
}

fn declare(b: &mut NodeBuilder) {
    b.doc("RMS relative error of a simulated series against a reference CSV (optionally time-anchored).");
    b.add_input::<Table>("series")
        .doc("The simulated series, with the columns named below.");
    b.add_input::<String>("reference")
        .file_in()
        .doc("Reference CSV with a header row.");
    b.add_input::<String>("x_column").default("T");
    b.add_input::<String>("y_column").default("Z");
    b.add_choice::<ErrorIn>("error_in")
        .doc("x: error in the arrival x of each reference y.");
    b.add_input::<f64>("anchor_x")
        .optional()
        .doc("Shift the simulation so that it reaches anchor_y at anchor_x.");
    b.add_input::<f64>("anchor_y").optional();
    b.add_input::<f64>("min_y")
        .default(f64::MIN)
        .doc("Only reference points with y >= min_y count.");
    b.add_output::<f64>("error");
    b.add_output::<Table>("table");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let t: Arc<Table> = ctx.input("series")?;
    let p: String = ctx.input("reference")?;
    let (xc, yc): (String, String) = (ctx.input("x_column")?, ctx.input("y_column")?);
    let path = ctx.input_path(&p);
    let text =
        std::fs::read_to_string(&path).map_err(|e| NodeError::io(&path, e).at("reference"))?;
    let reference = read_csv_columns(&text, &xc, &yc).map_err(|e| {
        // The error may quote the header row: only files of the run's own folders are
        // quoted, so a graph cannot read the first line of any file through it (issue 23).
        let e = if ctx.files().is_within_run_folders(&path) {
            e.to_string()
        } else {
            format!(
                "not a CSV with numeric columns '{xc}' and '{yc}' under a recognised header \
                 (its content is not shown: the file lies outside the graph's folder, the \
                 asset folders and the output directory)"
            )
        };
        NodeError::invalid("reference", format!("{}: {e}", Path::new(&p).display()))
    })?;
    let col = |c: &str| {
        t.column(c)
            .ok_or_else(|| NodeError::invalid("series", format!("the table has no column '{c}'")))
    };
    let sim: Vec<(f64, f64)> = col(&xc)?
        .iter()
        .copied()
        .zip(col(&yc)?.iter().copied())
        .collect();
    let anchor = match (
        ctx.input_opt::<f64>("anchor_x")?,
        ctx.input_opt::<f64>("anchor_y")?,
    ) {
        (Some(x), Some(y)) => Some((x, y)),
        (None, None) => None,
        _ => {
            return Err(NodeError::invalid(
                "anchor_y",
                "give both anchor_x and anchor_y, or neither",
            ))
        }
    };
    let error_in_x = ctx.choice::<ErrorIn>("error_in")? == ErrorIn::X;
    let min_y: f64 = ctx.input("min_y")?;
    let (rms, rows) = compare_series(&sim, &reference, error_in_x, anchor, min_y)
        .map_err(|e| NodeError::invalid("series", e.to_string()))?;
    let mut table = Table::with_columns(&["x_ref", "y_ref", "sim", "rel_error"]);
    for r in rows {
        table.push_row(&[r.0, r.1, r.2, r.3]);
    }
    table.meta.insert("rms_rel_error".into(), format!("{rms}"));
    ctx.set_output("error", rms);
    ctx.set_output("table", table);
    Ok(())
}

/// Registers `compare_series`.
pub fn register(r: &mut Registry) {
    r.add("compare_series", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_series_compared_with_itself_has_no_error_and_a_shift_is_undone_by_the_anchor() {
        let reference: Vec<(f64, f64)> = (0..20)
            .map(|i| (1.0 + i as f64 * 0.1, 1.0 + (i as f64 * 0.1).powi(2)))
            .collect();
        let (e, rows) = compare_series(&reference, &reference, true, None, 0.0).unwrap();
        assert!(e < 1e-12 && rows.len() == 20);
        // The simulation arrives 0.3 late everywhere: errors in x are 0.3 / x.
        let late: Vec<(f64, f64)> = reference.iter().map(|p| (p.0 + 0.3, p.1)).collect();
        let (e, rows) = compare_series(&late, &reference, true, None, 0.0).unwrap();
        let want =
            (rows.iter().map(|r| (0.3 / r.0).powi(2)).sum::<f64>() / rows.len() as f64).sqrt();
        assert!((e - want).abs() < 1e-12 && e > 0.1);
        // Anchored at a reference point, the shift disappears.
        let (e, _) = compare_series(&late, &reference, true, Some(reference[5]), 0.0).unwrap();
        assert!(e < 1e-12, "{e}");
        // Errors in y at the reference x.
        let high: Vec<(f64, f64)> = reference.iter().map(|p| (p.0, p.1 * 1.1)).collect();
        let (e, _) = compare_series(&high, &reference, false, None, 0.0).unwrap();
        assert!((e - 0.1).abs() < 1e-12);
        assert!(compare_series(&reference[..1], &reference, true, None, 0.0).is_err());
    }

    #[test]
    fn csv_columns_by_name() {
        let pts = read_csv_columns("T,Z\n0.5,1.1\n1.0,1.4\n", "T", "Z").unwrap();
        assert_eq!(pts, vec![(0.5, 1.1), (1.0, 1.4)]);
        assert!(read_csv_columns("T,Z\n0.5,x\n", "T", "Z")
            .unwrap_err()
            .to_string()
            .contains("row 2"));
        assert!(read_csv_columns("T,Q\n", "T", "Z")
            .unwrap_err()
            .to_string()
            .contains("no column 'Z'"));
    }
}
