//! `cgnodes sweep-merge`: joins the CSV parts of a sharded sweep into the CSV and chart an
//! unsharded sweep writes (see `crate::sweep_merge`).

use super::{SweepMergeArgs, EXIT_INVALID};
use crate::sweep::{to_chart, to_csv, SweepSpec};

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
    let (mut spec, rows) = crate::sweep_merge::merge(&parts).map_err(|e| e.to_string())?;
    let file = match &a.sweep {
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()))?;
            let f: SweepSpec =
                serde_json::from_str(&text).map_err(|e| format!("{}: {e}", p.display()))?;
            check_columns(&f, &spec).map_err(|e| format!("{}: {e}", p.display()))?;
            f
        }
        None => SweepSpec::default(),
    };
    a.chart.apply(&mut spec, &file);
    let text = to_csv(&spec, &rows);
    match &a.csv {
        Some(p) => crate::io::write_atomic(p, |w| w.write_all(text.as_bytes()))
            .map_err(|e| format!("{}: {e}", p.display()))?,
        None => print!("{text}"),
    }
    if let Some(plot) = &a.plot {
        let chart = to_chart(&spec, &rows).map_err(|e| e.to_string())?;
        crate::chart::draw(&chart, plot).map_err(|e| e.to_string())?;
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
fn check_columns(file: &SweepSpec, merged: &SweepSpec) -> Result<(), String> {
    let names = |s: &SweepSpec| s.vary.iter().map(|v| v.param.clone()).collect::<Vec<_>>();
    if names(file) != names(merged) || file.measure != merged.measure {
        return Err(format!(
            "mismatched columns: the sweep varies [{}] and measures [{}], the parts [{}] and [{}]",
            names(file).join(", "),
            file.measure.join(", "),
            names(merged).join(", "),
            merged.measure.join(", ")
        ));
    }
    for (f, m) in file.vary.iter().zip(&merged.vary) {
        if let Some(x) = m.values.iter().find(|x| !f.values.contains(x)) {
            return Err(format!(
                "the parts have {}={x}, which the sweep does not vary over",
                f.param
            ));
        }
    }
    Ok(())
}
