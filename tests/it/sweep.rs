//! `cgnodes sweep`: every combination runs, failures are recorded without stopping the
//! sweep, upstream nodes are served from the cache, and the CSV and chart are written.

use cgnodes::registry::Registry;
use cgnodes::sweep::{parse_vary, run_and_write, SweepSpec};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

const GRAPH: &str = r#"{"format":"cgnodes-graph","version":1,"nodes":{
  "source":{"type":"slow_source","params":{"value":8}},
  "d":{"type":"math","params":{"op":"div","b":2},"inputs":{"a":"source.value"}},
  "err":{"type":"math","params":{"op":"sub","b":4},"inputs":{"a":"d.value"}},
  "w":{"type":"table_write","params":{"path":"e.csv"},"inputs":{"value":"err.value"}}}}"#;

fn registry(count: Arc<Mutex<HashMap<String, usize>>>) -> Registry {
    let mut r = cgnodes::nodes::builtin_registry();
    r.add(
        "slow_source",
        |b| {
            b.add_input::<f64>("value").default(1.0);
            b.add_output::<f64>("value");
        },
        move |ctx| {
            *count
                .lock()
                .unwrap()
                .entry(ctx.node_id.to_string())
                .or_default() += 1;
            let v: f64 = ctx.input("value")?;
            ctx.set_output("value", v);
            Ok(())
        },
    );
    r
}

#[test]
fn a_sweep_records_every_combination_and_failure_and_reuses_upstream_results() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("g.json"), GRAPH).unwrap();
    let counts: Arc<Mutex<HashMap<String, usize>>> = Arc::default();
    let r = registry(counts.clone());
    let spec = SweepSpec {
        graph: "g.json".into(),
        vary: vec![
            parse_vary("d.b=0,1,2,4").unwrap(),
            parse_vary("d.op=div,mul").unwrap(),
        ],
        repeat: 2,
        measure: vec!["err.value".into(), "d.value".into()],
        csv: Some("sweep.csv".into()),
        plot: Some("sweep.svg".into()),
        x: Some("d.b".into()),
        y: Some("err.value".into()),
        ..Default::default()
    };
    let rows = run_and_write(&spec, dir.path(), &r, Some(2)).unwrap();
    assert_eq!(rows.len(), 4 * 2 * 2);
    // The CSV (sidecar) and the chart (SVG comment) say what made them.
    let graph_hash =
        cgnodes::node::Provenance::hash_graph(&std::fs::read(dir.path().join("g.json")).unwrap());
    for f in ["sweep.csv", "sweep.svg"] {
        let p = cgnodes::node::Provenance::read(&dir.path().join(f)).unwrap();
        assert_eq!(
            (p.node.as_str(), p.params["repeat"].as_u64()),
            ("sweep", Some(2)),
            "{f}"
        );
        assert_eq!(p.graph_hash, graph_hash, "{f}");
        assert_eq!(p.params["vary"][1]["param"], "d.op", "{f}");
    }
    // Division by zero fails (twice: two repeats) and the sweep goes on.
    let failed: Vec<_> = rows.iter().filter(|r| !r.ok).collect();
    assert_eq!(failed.len(), 2);
    assert!(failed
        .iter()
        .all(|r| r.error_kind == "invalid_input" && r.error.contains("d (math)")));
    // Measured values are right: 8 / b - 4 and 8 * b - 4.
    for row in rows.iter().filter(|r| r.ok) {
        let b = row.values[0].as_f64().unwrap();
        let want = if row.values[1] == "div" {
            8.0 / b - 4.0
        } else {
            8.0 * b - 4.0
        };
        assert_eq!(row.measures[0], want);
    }
    // The upstream node ran once for the whole sweep.
    assert_eq!(counts.lock().unwrap()["source"], 1);
    // Repeats re-executed the varied node (its time is real, not a cache hit).
    assert!(rows
        .iter()
        .filter(|r| r.ok && r.repeat == 1)
        .all(|r| r.node_ms["d"] > 0.0));
    let csv = std::fs::read_to_string(dir.path().join("sweep.csv")).unwrap();
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        &head[..7],
        [
            "d.b",
            "d.op",
            "repeat",
            "status",
            "error_kind",
            "error",
            "total_ms"
        ]
    );
    assert!(head.contains(&"ms:source") && head.ends_with(&["err.value", "d.value"]));
    assert_eq!(lines.clone().count(), 16);
    assert_eq!(
        lines
            .filter(|l| l.contains(",failed,invalid_input,"))
            .count(),
        2
    );
    let svg = std::fs::read_to_string(dir.path().join("sweep.svg")).unwrap();
    assert!(
        svg.contains("<svg")
            && svg.contains("failed (2)")
            && svg.contains("div")
            && svg.contains("mul")
    );
}

#[test]
fn a_sweep_file_through_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let graph = concat!(env!("CARGO_MANIFEST_DIR"), "/graphs/arithmetic.json");
    let sweep = serde_json::json!({
        "graph": graph,
        "vary": [{"param": "radius.value", "values": [1, 2, 3]}],
        "measure": ["pi_r2.value"],
        "csv": "areas.csv",
        "plot": "areas.png",
        "x": "radius.value"
    });
    std::fs::write(dir.path().join("sweep.json"), sweep.to_string()).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_cgnodes"))
        .args(["sweep", dir.path().join("sweep.json").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // One row per radius, in the order given, each with the area of its own radius.
    let csv = std::fs::read_to_string(dir.path().join("areas.csv")).unwrap();
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| {
        head.iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("no column {name} in {head:?}"))
    };
    let (rc, ac) = (col("radius.value"), col("pi_r2.value"));
    let rows: Vec<(f64, f64)> = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[rc].parse().unwrap(), f[ac].parse().unwrap())
        })
        .collect();
    assert_eq!(rows.len(), 3, "{csv}");
    for ((r, a), want_r) in rows.iter().zip([1.0, 2.0, 3.0]) {
        assert_eq!(*r, want_r, "{csv}");
        assert!((a - std::f64::consts::PI * r * r).abs() < 1e-9, "{csv}");
    }
    assert!(image::open(dir.path().join("areas.png")).is_ok());
    // A measure that does not exist is an error, not a silent empty column.
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_cgnodes"))
        .args([
            "sweep",
            graph,
            "--vary",
            "radius.value=1,2",
            "--measure",
            "pi_r2.nope",
        ])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("no output pi_r2.nope"));
}

#[test]
fn chart_puts_a_sweep_and_a_peer_on_one_plot() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("ours.csv"),
        "method,status,total_ms,rmse\nmis,ok,10,0.5\nmis,ok,40,0.25\nmis,failed,5,\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("peer.csv"),
        "method,total_ms,rmse\n\"mitsuba, scalar\",20,0.5\n\"mitsuba, scalar\",80,0.25\n",
    )
    .unwrap();
    let plot = dir.path().join("c.svg");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_cgnodes"))
        .args([
            "chart", "--x", "total_ms", "--y", "rmse", "--series", "method", "--log-x", "--plot",
        ])
        .arg(&plot)
        .arg(dir.path().join("ours.csv"))
        .arg(dir.path().join("peer.csv"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let svg = std::fs::read_to_string(&plot).unwrap();
    assert!(svg.contains("mis") && svg.contains("mitsuba, scalar") && svg.contains("failed (1)"));
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_cgnodes"))
        .args(["chart", "--x", "nope", "--y", "rmse", "--plot"])
        .arg(&plot)
        .arg(dir.path().join("ours.csv"))
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("no column 'nope'"));
}

/// Over frames, a metric that cannot be computed before the last frame (its series is still
/// too short) does not end the run, while a simulation failing on an earlier frame does.
#[test]
fn a_sweep_over_frames_counts_metric_failures_only_at_the_last_frame() {
    let dir = tempfile::tempdir().unwrap();
    let graph = r#"{"format":"cgnodes-graph","version":1,"nodes":{
      "grid":{"type":"mesh_grid","params":{"cells_u":2,"cells_v":2}},
      "sim":{"type":"mass_spring","inputs":{"mesh":"grid.mesh"},
             "params":{"integrator":"semi_implicit","h":0.001,"substeps":10,"fixed":"top_corners"}},
      "cmp":{"type":"compare_series","inputs":{"series":"sim.log"},
             "params":{"reference":"ref.csv","x_column":"time","y_column":"kinetic","error_in":"y"}}},
      "outputs":["cmp"]}"#;
    std::fs::write(dir.path().join("g.json"), graph).unwrap();
    // Inside the last frame's steps (t = 0.011 ... 0.02) only.
    std::fs::write(
        dir.path().join("ref.csv"),
        "time,kinetic\n0.012,0.001\n0.018,0.002\n",
    )
    .unwrap();
    let spec = SweepSpec {
        graph: "g.json".into(),
        vary: vec![parse_vary("sim.h=0.001,0.5").unwrap()],
        measure: vec!["cmp.error".into()],
        frames: Some("0..2".into()),
        ..Default::default()
    };
    let rows = run_and_write(
        &spec,
        dir.path(),
        &cgnodes::nodes::builtin_registry(),
        Some(1),
    )
    .unwrap();
    assert_eq!(rows.len(), 2);
    assert!(rows[0].ok, "{}", rows[0].error);
    assert!(rows[0].measures[0].is_finite());
    assert!(!rows[1].ok);
    assert_eq!(rows[1].error_kind, "unstable");
    assert!(rows[1].error.starts_with("frame 1:"), "{}", rows[1].error);
}

/// A measured node runs even when the graph's outputs do not include it (metric nodes are
/// rarely writers), and only the requested work runs besides it.
#[test]
fn measured_nodes_run_although_the_graph_outputs_leave_them_out() {
    let dir = tempfile::tempdir().unwrap();
    let graph = r#"{"format":"cgnodes-graph","version":1,"nodes":{
      "source":{"type":"slow_source","params":{"value":8}},
      "half":{"type":"math","params":{"op":"div","b":2},"inputs":{"a":"source.value"}},
      "w":{"type":"table_write","params":{"path":"e.csv"},"inputs":{"value":"source.value"}}},
      "outputs":["w"]}"#;
    std::fs::write(dir.path().join("g.json"), graph).unwrap();
    let counts: Arc<Mutex<HashMap<String, usize>>> = Arc::default();
    let r = registry(counts.clone());
    let spec = SweepSpec {
        graph: "g.json".into(),
        vary: vec![parse_vary("source.value=2,6").unwrap()],
        measure: vec!["half.value".into()],
        ..Default::default()
    };
    let rows = run_and_write(&spec, dir.path(), &r, Some(1)).unwrap();
    assert_eq!(rows.len(), 2);
    assert!(rows.iter().all(|r| r.ok), "{}", rows[0].error);
    assert_eq!(rows[0].measures[0], 1.0);
    assert_eq!(rows[1].measures[0], 3.0);
    // The writer the graph asks for ran too.
    assert!(rows[0].node_ms.contains_key("w"), "{:?}", rows[0].node_ms);
}
