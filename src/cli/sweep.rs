//! `cgnodes sweep`: reads a sweep file or a graph, applies the command line's options, runs
//! the sweep and writes its CSV and chart (the CSV goes to stdout when no file is named).

use super::{SweepArgs, EXIT_INVALID, EXIT_USAGE};
use crate::registry::Registry;
use crate::sweep::{parse_vary, run_and_write, to_csv, SweepSpec};
use std::path::{Path, PathBuf};

/// `cgnodes sweep TARGET ...`: the command line's options override the sweep file's.
pub(super) fn cmd(registry: &Registry, a: SweepArgs) -> i32 {
    let raw: Option<serde_json::Value> = std::fs::read_to_string(&a.target)
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok());
    let is_sweep_file = raw
        .as_ref()
        .is_some_and(|r| r.get("graph").is_some() && r.get("nodes").is_none());
    let (mut spec, base) = if is_sweep_file {
        match serde_json::from_value::<SweepSpec>(raw.unwrap_or_default()) {
            Ok(s) => (
                s,
                a.target.parent().map(Path::to_path_buf).unwrap_or_default(),
            ),
            Err(e) => {
                eprintln!("error: {}: {e}", a.target.display());
                return EXIT_INVALID;
            }
        }
    } else {
        (
            SweepSpec {
                graph: a.target.clone(),
                repeat: 1,
                ..Default::default()
            },
            PathBuf::from("."),
        )
    };
    for v in &a.vary {
        match parse_vary(v) {
            Ok(v) => spec.vary.push(v),
            Err(e) => {
                eprintln!("error: {e}");
                return EXIT_USAGE;
            }
        }
    }
    spec.set.extend(a.set);
    spec.measure.extend(a.measure);
    if let Some(r) = a.repeat {
        spec.repeat = r;
    }
    // Paths given on the command line are relative to the current folder.
    let here = |p: PathBuf| {
        if is_sweep_file && p.is_relative() {
            std::env::current_dir().unwrap_or_default().join(p)
        } else {
            p
        }
    };
    // A shard writes only the part it is given on the command line: the sweep file's CSV
    // and chart are the merge's (`cgnodes sweep-merge`), and shards must not all write them.
    let sharded = a.shard.shard.is_some();
    if sharded && a.csv.is_none() {
        eprintln!("error: --shard: give --csv PART.csv, one file per shard (cgnodes sweep-merge joins them)");
        return EXIT_USAGE;
    }
    spec.csv = a.csv.map(here).or(spec.csv);
    spec.plot = a.plot.map(here).or(spec.plot.filter(|_| !sharded));
    spec.out = a.out.map(here).or(spec.out);
    let file = spec.clone();
    a.chart.apply(&mut spec, &file);
    spec.frames = a.frames.or(spec.frames);
    spec.max_memory = a.max_memory.or(spec.max_memory);
    spec.shard = match a.shard.resolve() {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_USAGE;
        }
    };
    spec.cache = a.cache;
    let monitor = super::progress::Monitor::new(super::progress::Verbosity::Normal);
    spec.progress = monitor.sweep_progress();
    match run_and_write(&spec, &base, registry, a.threads) {
        Ok(rows) => {
            let failed = rows.iter().filter(|r| !r.ok).count();
            match spec.shard {
                Some(s) => eprintln!("shard {s}: {} runs, {} failed", rows.len(), failed),
                None => eprintln!("{} runs, {} failed", rows.len(), failed),
            }
            if spec.csv.is_none() {
                print!("{}", to_csv(&spec, &rows));
            }
            if !sharded {
                sweep_report(&spec, &base, &a.target, registry);
            }
            0
        }
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_INVALID
        }
    }
}

/// Writes `report.html` for a sweep beside its CSV (or in its `out` folder): the chart and
/// the CSV. Nothing when the sweep writes neither.
fn sweep_report(spec: &SweepSpec, base: &Path, target: &Path, registry: &Registry) {
    let files: Vec<PathBuf> = [&spec.plot, &spec.csv]
        .into_iter()
        .flatten()
        .map(|p| base.join(p))
        .collect();
    let dir = match (&spec.out, files.last()) {
        (Some(o), _) => base.join(o),
        (None, Some(f)) => f.parent().map(Path::to_path_buf).unwrap_or_default(),
        (None, None) => return,
    };
    let dir = if dir.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        dir
    };
    match crate::report::write_sweep_report(
        &target.display().to_string(),
        &files,
        &dir,
        registry.mesh_hooks,
    ) {
        Ok(p) => eprintln!("report: {}", p.display()),
        Err(e) => eprintln!("warning: report not written: {e}"),
    }
}
