//! Live feedback: node log lines reach the log sink while the node runs (before its progress
//! ends), long nodes report progress, and the command line's `-q`, `-v` and plain progress
//! lines (off a terminal) say what they should.

use crate::common::{asset, root};
use cgnodes::exec::{Executor, RunOptions};
use cgnodes::node::{FileEnv, LogFn, LogLevel, ProgressFn};
use std::process::Command;
use std::sync::{Arc, Mutex};

/// A Tutte start and 8 ARAP iterations on the course's 20x20 grid (a disk).
fn arap_graph() -> String {
    let grid = asset("assets/course/grid20x20.usda");
    format!(
        r#"{{"format": "cgnodes-graph", "version": 1, "nodes": {{
          "load": {{"type": "mesh_load", "params": {{"path": {grid:?}}}}},
          "arap": {{"type": "arap", "params": {{"iterations": 8, "tolerance": 0}},
                   "inputs": {{"mesh": "load.mesh"}}}}
        }}, "outputs": ["arap"]}}"#
    )
}

#[derive(Debug, PartialEq)]
enum Event {
    Log(String, LogLevel),
    Progress(String, f64),
}

#[test]
fn log_lines_stream_before_the_node_ends_and_arap_reports_its_iterations() {
    let reg = cgnodes::nodes::builtin_registry();
    let dir = tempfile::tempdir().unwrap();
    let g = cgnodes::graph::parse(&arap_graph(), &dir.path().join("g.json"), dir.path()).unwrap();
    let valid = cgnodes::validate::validate(&g, &reg).unwrap();
    let events = Arc::new(Mutex::new(Vec::new()));
    let (e1, e2) = (events.clone(), events.clone());
    let log: LogFn = Arc::new(move |node: &str, level: LogLevel, line: &str| {
        e1.lock()
            .unwrap()
            .push(Event::Log(format!("{node}: {line}"), level));
    });
    let progress: ProgressFn = Arc::new(move |node: &str, f: f64| {
        e2.lock().unwrap().push(Event::Progress(node.into(), f));
    });
    let opts = RunOptions {
        files: FileEnv {
            graph_dir: dir.path().into(),
            out_dir: dir.path().into(),
            ..Default::default()
        },
        progress: Some(progress),
        log: Some(log),
        ..Default::default()
    };
    let report = Executor::new(Some(1), None).unwrap().run(&valid, &opts, 0);
    assert!(report.ok(), "{:?}", report.errors());
    let ev = events.lock().unwrap();
    let arap_progress: Vec<f64> = ev
        .iter()
        .filter_map(|e| match e {
            Event::Progress(n, f) if n == "arap" => Some(*f),
            _ => None,
        })
        .collect();
    // One report per iteration (0/8 .. 7/8), then the executor's end-of-node 1.
    assert!(arap_progress.len() >= 9, "{arap_progress:?}");
    assert!(arap_progress.windows(2).all(|w| w[1] >= w[0]));
    assert_eq!(arap_progress.last(), Some(&1.0));
    // The start note is logged before the iterations: it must arrive before the first
    // progress report, not when the frame ends.
    let first_log = ev
        .iter()
        .position(|e| matches!(e, Event::Log(l, _) if l.starts_with("arap: ")))
        .expect("arap logs");
    let first_progress = ev
        .iter()
        .position(|e| matches!(e, Event::Progress(n, _) if n == "arap"))
        .unwrap();
    assert!(first_log < first_progress, "{ev:?}");
    // The sink saw every line the report keeps, at its level.
    let node = report.node("arap").unwrap();
    for l in &node.logs {
        assert!(ev.contains(&Event::Log(format!("arap: {l}"), LogLevel::of(l))));
    }
    assert_eq!(LogLevel::of("warning: x"), LogLevel::Warning);
}

fn cgnodes(args: &[&str], env: &[(&str, &str)]) -> (bool, String) {
    let mut c = Command::new(env!("CARGO_BIN_EXE_cgnodes"));
    c.args(args).current_dir(root());
    for (k, v) in env {
        c.env(k, v);
    }
    let o = c.output().unwrap();
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn quiet_verbose_and_plain_progress_lines() {
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("g.json");
    std::fs::write(&g, arap_graph()).unwrap();
    let out = dir.path().join("out");
    let (g, out) = (g.to_str().unwrap(), out.to_str().unwrap());
    let (ok, quiet) = cgnodes(&["run", g, "--out", out, "-q"], &[]);
    assert!(ok && quiet.trim().is_empty(), "-q printed: {quiet}");
    let (ok, normal) = cgnodes(&["run", g, "--out", out], &[]);
    assert!(ok && normal.contains("arap: ") && !normal.contains("(arap): ran in"));
    let (ok, verbose) = cgnodes(&["run", g, "--out", out, "-v"], &[]);
    assert!(ok && verbose.contains("arap (arap): ran in"), "{verbose}");
    // The second run's load is cached in memory only within a process: each command runs it.
    assert!(verbose.contains("load (mesh_load): ran in"), "{verbose}");
    // Off a terminal, progress lines appear once a task has run CGNODES_PROGRESS_AFTER seconds.
    let (ok, plain) = cgnodes(
        &["run", g, "--out", out, "--frames", "0..2"],
        &[("CGNODES_PROGRESS_AFTER", "0"), ("CI", "1")],
    );
    assert!(ok, "{plain}");
    assert!(
        plain.contains("[frame 0] arap: ") && plain.contains("% after"),
        "{plain}"
    );
    assert!(
        plain.contains("frames: ") && plain.contains("frames, ETA"),
        "{plain}"
    );
}
