//! `cgnodes sweep-merge`: joins the CSV parts of a sharded sweep into the CSV and chart an
//! unsharded sweep writes (see `crate::sweep_merge`).

use super::{SweepMergeArgs, EXIT_INVALID};
use crate::sweep::{to_chart, to_csv};

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

fn merge(a: &SweepMergeArgs) -> Result<(), String> {
    let parts = a
        .parts
        .iter()
        .map(|p| {
            std::fs::read_to_string(p)
                .map(|t| (p.display().to_string(), t))
                .map_err(|e| format!("{}: {e}", p.display()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let (mut spec, rows) = crate::sweep_merge::merge(&parts)?;
    spec.x = a.x.clone();
    spec.y = a.y.clone();
    spec.series = a.series.clone();
    spec.title = a.title.clone();
    spec.log_x = a.log_x;
    spec.log_y = a.log_y;
    let text = to_csv(&spec, &rows);
    match &a.csv {
        Some(p) => crate::io::write_atomic(p, |w| w.write_all(text.as_bytes()))
            .map_err(|e| format!("{}: {e}", p.display()))?,
        None => print!("{text}"),
    }
    if let Some(plot) = &a.plot {
        crate::chart::draw(&to_chart(&spec, &rows)?, plot)?;
    }
    let failed = rows.iter().filter(|r| !r.ok).count();
    eprintln!(
        "merged {} parts: {} runs, {failed} failed",
        parts.len(),
        rows.len()
    );
    Ok(())
}
