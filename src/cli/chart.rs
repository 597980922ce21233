//! `cgnodes chart`: charts columns of one or more CSV files (a sweep beside a peer's
//! results, say), one series per file or per value of a column.

use super::{ChartArgs, FileError, EXIT_INVALID};
use crate::chart::{draw, Chart, ChartError, Series};
use crate::io::csv::read;
use std::path::PathBuf;

/// Why `cgnodes chart` could not chart its CSV files.
#[derive(Debug, thiserror::Error)]
enum ChartCmdError {
    /// A CSV file could not be read.
    #[error(transparent)]
    File(#[from] FileError),
    /// A CSV file that does not parse (the CSV reader's message).
    #[error("{}: {message}", .path.display())]
    Csv {
        /// The file.
        path: PathBuf,
        /// The reader's message.
        message: String,
    },
    /// A CSV file without a header.
    #[error("{}: empty", .0.display())]
    Empty(PathBuf),
    /// A column named by `--x`, `--y` or `--series` that the file lacks.
    #[error("{}: no column '{name}'", .path.display())]
    NoColumn {
        /// The file.
        path: PathBuf,
        /// The column.
        name: String,
    },
    /// The chart could not be drawn.
    #[error("{0}")]
    Draw(#[from] ChartError),
}

/// `cgnodes chart CSV... --x X --y Y --plot FILE`.
pub(super) fn cmd(a: &ChartArgs) -> i32 {
    match chart_from_csv(a) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_INVALID
        }
    }
}

fn chart_from_csv(a: &ChartArgs) -> Result<(), ChartCmdError> {
    let mut chart = Chart {
        title: a.title.clone(),
        x_label: a.x.clone(),
        y_label: a.y.clone(),
        log_x: a.log_x,
        log_y: a.log_y,
        ..Default::default()
    };
    for f in &a.csv {
        let text = std::fs::read_to_string(f).map_err(FileError::at(f))?;
        let csv = read(&text, false, false)
            .map_err(|message| ChartCmdError::Csv {
                path: f.clone(),
                message,
            })?
            .ok_or_else(|| ChartCmdError::Empty(f.clone()))?;
        let col = |name: &str| {
            csv.column(name).ok_or_else(|| ChartCmdError::NoColumn {
                path: f.clone(),
                name: name.into(),
            })
        };
        let (ix, iy) = (col(&a.x)?, col(&a.y)?);
        let is = a.series.as_deref().map(col).transpose()?;
        let status = csv.column("status");
        let file_label = f
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_default();
        for row in &csv.rows {
            let num = |i: usize| row.get(i).and_then(|s| s.trim().parse::<f64>().ok());
            let Some(x) = num(ix) else { continue };
            if status
                .and_then(|i| row.get(i))
                .is_some_and(|s| s == "failed")
            {
                chart.failures.push((x, file_label.clone()));
                continue;
            }
            let Some(y) = num(iy) else { continue };
            let label = match is {
                Some(i) => row.get(i).cloned().unwrap_or_default(),
                None => file_label.clone(),
            };
            match chart.series.iter_mut().find(|s| s.label == label) {
                Some(s) => s.points.push((x, y)),
                None => chart.series.push(Series {
                    label,
                    points: vec![(x, y)],
                }),
            }
        }
    }
    for s in &mut chart.series {
        s.points.sort_by(|p, q| p.0.total_cmp(&q.0));
    }
    Ok(draw(&chart, &a.plot)?)
}
