//! `cgnodes sweep-merge`: joins the CSV parts of a sharded sweep into the CSV and chart an
//! unsharded sweep writes (see `crate::sweep_merge`).

use super::{FileError, SweepMergeArgs, EXIT_INVALID};
use crate::chart::ChartError;
use crate::sweep::{to_chart, to_csv, AxisError, SweepSpec};
use crate::sweep_merge::MergeError;

/// Why `sweep-merge` could not join the parts.
#[derive(Debug, thiserror::Error)]
enum SweepMergeError {
    /// A part, the sweep file or the CSV written.
    #[error(transparent)]
    File(#[from] FileError),
    /// The parts do not join.
    #[error(transparent)]
    Merge(#[from] MergeError),
    /// The chart's axes do not fit the merged rows.
    #[error(transparent)]
    Axis(#[from] AxisError),
    /// The chart could not be drawn.
    #[error(transparent)]
    Chart(#[from] ChartError),
}

/// The parts' columns do not match the sweep file named with `--sweep`.
#[derive(Debug, thiserror::Error)]
enum ColumnMismatch {
    /// Other varied parameters or measures.
    #[error("mismatched columns: the sweep varies [{}] and measures [{}], the parts [{}] and [{}]", .file_vary.join(", "), .file_measure.join(", "), .parts_vary.join(", "), .parts_measure.join(", "))]
    Columns {
        /// The sweep file's varied parameters.
        file_vary: Vec<String>,
        /// The sweep file's measures.
        file_measure: Vec<String>,
        /// The parts' varied parameters.
        parts_vary: Vec<String>,
        /// The parts' measures.
        parts_measure: Vec<String>,
    },
    /// A value of a parameter the sweep does not take.
    #[error("the parts have {param}={value}, which the sweep does not vary over")]
    Value {
        /// The parameter.
        param: String,
        /// The value in the parts.
        value: serde_json::Value,
    },
}

/// `cgnodes sweep-merge PART... [--csv FILE] [--plot FILE]`.
pub(super) fn cmd(a: &SweepMergeArgs) -> i32 {
    match merge(a) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_INVALID
        }
    }
}

fn merge(a: &SweepMergeArgs) -> Result<(), SweepMergeError> {
    let parts = a
        .parts
        .iter()
        .map(|p| {
            std::fs::read_to_string(p)
                .map(|t| (p.display().to_string(), t))
                .map_err(FileError::at(p))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let (mut spec, rows) = crate::sweep_merge::merge(&parts)?;
    let file = match &a.sweep {
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(FileError::at(p))?;
            let f: SweepSpec = serde_json::from_str(&text).map_err(FileError::at(p))?;
            check_columns(&f, &spec).map_err(FileError::at(p))?;
            f
        }
        None => SweepSpec::default(),
    };
    a.chart.apply(&mut spec, &file);
    let text = to_csv(&spec, &rows);
    match &a.csv {
        Some(p) => crate::io::write_atomic(p, |w| w.write_all(text.as_bytes()))
            .map_err(FileError::at(p))?,
        None => print!("{text}"),
    }
    if let Some(plot) = &a.plot {
        let chart = to_chart(&spec, &rows)?;
        crate::chart::draw(&chart, plot)?;
    }
    let failed = rows.iter().filter(|r| !r.ok).count();
    eprintln!(
        "merged {} parts: {} runs, {failed} failed",
        parts.len(),
        rows.len()
    );
    Ok(())
}

/// The parts must come from the sweep file named: the same varied parameters, values among
/// its values, the same measures.
fn check_columns(file: &SweepSpec, merged: &SweepSpec) -> Result<(), ColumnMismatch> {
    let names = |s: &SweepSpec| s.vary.iter().map(|v| v.param.clone()).collect::<Vec<_>>();
    if names(file) != names(merged) || file.measure != merged.measure {
        return Err(ColumnMismatch::Columns {
            file_vary: names(file),
            file_measure: file.measure.clone(),
            parts_vary: names(merged),
            parts_measure: merged.measure.clone(),
        });
    }
    for (f, m) in file.vary.iter().zip(&merged.vary) {
        if let Some(x) = m.values.iter().find(|x| !f.values.contains(x)) {
            return Err(ColumnMismatch::Value {
                param: f.param.clone(),
                value: x.clone(),
            });
        }
    }
    Ok(())
}
