//! The graph runtime: validation errors, planning, parallel execution, caching, frames,
//! atomic writes, path safety and command-line overrides.

use cgnodes::exec::{Executor, NodeStatus, RunOptions, RunReport};
use cgnodes::graph::{self, Graph};
use cgnodes::node::{FileEnv, NodeError};
use cgnodes::registry::Registry;
use cgnodes::validate::{validate, GraphError, ValidGraph};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

fn data(name: &str) -> PathBuf {
    crate::common::asset("tests/data").join(name)
}

fn errors_of(name: &str) -> Vec<GraphError> {
    let g = graph::load(&data(&format!("bad/{name}"))).expect("loads");
    match validate(&g, &cgnodes::nodes::builtin_registry()) {
        Ok(_) => panic!("{name} should not validate"),
        Err(e) => e,
    }
}

fn parse(text: &str) -> Graph {
    graph::parse(text, Path::new("inline.json"), Path::new(".")).expect("parses")
}

fn opts(out: &Path) -> RunOptions {
    RunOptions {
        files: FileEnv {
            out_dir: out.to_path_buf(),
            ..Default::default()
        },
        ..Default::default()
    }
}

/// A registry with the built-in nodes plus test nodes that count their executions.
fn counting_registry(counts: Arc<Mutex<HashMap<String, usize>>>) -> Registry {
    let mut r = cgnodes::nodes::builtin_registry();
    let c = counts.clone();
    r.add(
        "count_add",
        |b| {
            b.add_input::<f64>("x").default(0.0);
            b.add_input::<f64>("k").default(1.0);
            b.add_output::<f64>("value");
        },
        move |ctx| {
            *c.lock()
                .unwrap()
                .entry(ctx.node_id.to_string())
                .or_default() += 1;
            let v = ctx.input::<f64>("x")? + ctx.input::<f64>("k")?;
            ctx.set_output("value", v);
            Ok(())
        },
    );
    let c = counts;
    r.add(
        "accumulate",
        |b| {
            b.stateful();
            b.add_input::<f64>("x").default(1.0);
            b.add_output::<f64>("total");
        },
        move |ctx| {
            *c.lock()
                .unwrap()
                .entry(ctx.node_id.to_string())
                .or_default() += 1;
            let x: f64 = ctx.input("x")?;
            let st = ctx.state::<f64>()?;
            *st += x;
            let t = *st;
            ctx.set_output("total", t);
            Ok(())
        },
    );
    r
}

fn valid(g: &Graph, r: &Registry) -> ValidGraph {
    validate(g, r)
        .unwrap_or_else(|e| panic!("{:?}", e.iter().map(|e| e.to_string()).collect::<Vec<_>>()))
}

// ---------------------------------------------------------------- validation errors

#[test]
fn unknown_node_type_suggests_the_closest_name() {
    let e = errors_of("unknown_type.json");
    let msg = e[0].to_string();
    assert!(
        matches!(&e[0], GraphError::UnknownNodeType { node, .. } if node == "a"),
        "{msg}"
    );
    assert!(
        msg.contains("unknown_type.json") && msg.contains("'a'") && msg.contains("value_flaot"),
        "{msg}"
    );
    assert!(msg.contains("did you mean 'value_float'"), "{msg}");
}

#[test]
fn unknown_input_socket_names_node_and_socket() {
    let e = errors_of("unknown_socket.json");
    let msg = e
        .iter()
        .map(|e| e.to_string())
        .collect::<Vec<_>>()
        .join("\n");
    assert!(e.iter().any(|e| matches!(e, GraphError::UnknownSocket { node, socket, .. } if node == "a" && socket == "valeu")), "{msg}");
    assert!(
        msg.contains("(value_float)") && msg.contains("did you mean 'value'"),
        "{msg}"
    );
}

#[test]
fn unknown_output_socket_in_a_link() {
    let e = errors_of("unknown_output_socket.json");
    let msg = e[0].to_string();
    assert!(
        matches!(&e[0], GraphError::UnknownSocket { node, socket, side: cgnodes::validate::Side::Output, .. } if node == "a" && socket == "result"),
        "{msg}"
    );
}

#[test]
fn missing_required_input() {
    let e = errors_of("missing_input.json");
    let msg = e[0].to_string();
    assert!(
        matches!(&e[0], GraphError::MissingInput { node, socket, .. } if node == "p" && socket == "value"),
        "{msg}"
    );
    assert!(msg.contains("(print)"), "{msg}");
}

#[test]
fn type_mismatch_names_both_ends() {
    let e = errors_of("type_mismatch.json");
    let msg = e[0].to_string();
    assert!(
        matches!(&e[0], GraphError::MismatchedInputSlotType { node, socket, from_node, .. } if node == "m" && socket == "a" && from_node == "s"),
        "{msg}"
    );
    assert!(
        msg.contains("expects float") && msg.contains("'s.value' gives string"),
        "{msg}"
    );
}

#[test]
fn parameter_outside_its_choices_or_range() {
    let e = errors_of("out_of_range.json");
    let msg = e[0].to_string();
    assert!(
        matches!(&e[0], GraphError::BadParam { node, socket, .. } if node == "m" && socket == "op"),
        "{msg}"
    );
    assert!(msg.contains("'modulo' is not one of"), "{msg}");
    // A numeric range, on a node declared in this test.
    let mut r = cgnodes::nodes::builtin_registry();
    r.add(
        "clamped",
        |b| {
            b.sink();
            b.add_input::<f64>("x").range(0.0, 1.0).default(0.5);
        },
        |_| Ok(()),
    );
    let g = parse(
        r#"{"format":"cgnodes-graph","version":1,"nodes":{"c":{"type":"clamped","params":{"x":2.5}}}}"#,
    );
    let e = validate(&g, &r).unwrap_err();
    assert!(
        e[0].to_string().contains("2.5 is above the maximum 1"),
        "{}",
        e[0]
    );
}

#[test]
fn parameter_of_the_wrong_kind() {
    let e = errors_of("wrong_kind.json");
    let msg = e[0].to_string();
    assert!(
        matches!(&e[0], GraphError::BadParam { node, socket, .. } if node == "i" && socket == "value"),
        "{msg}"
    );
    assert!(msg.contains("expected an integer"), "{msg}");
}

#[test]
fn literal_and_link_on_one_socket() {
    let e = errors_of("literal_and_link.json");
    assert!(
        matches!(&e[0], GraphError::LiteralAndLink { node, socket, .. } if node == "m" && socket == "a"),
        "{}",
        e[0]
    );
}

#[test]
fn dangling_link() {
    let e = errors_of("dangling_link.json");
    let msg = e[0].to_string();
    assert!(
        matches!(&e[0], GraphError::DanglingLink { node, socket, .. } if node == "m" && socket == "a"),
        "{msg}"
    );
    assert!(msg.contains("no node 'ghost'"), "{msg}");
}

#[test]
fn cycle_lists_the_nodes_around_it() {
    let e = errors_of("cycle.json");
    match &e[0] {
        GraphError::Cycle { path, .. } => assert_eq!(path, &["a", "b", "c", "a"]),
        other => panic!("{other}"),
    }
}

#[test]
fn malformed_json_gives_line_and_column() {
    let e = graph::load(&data("bad/malformed.json")).unwrap_err();
    match &e {
        graph::LoadError::Parse { line, column, .. } => {
            assert_eq!(*line, 3);
            assert!(*column > 20);
        }
        other => panic!("{other}"),
    }
    assert!(e.to_string().contains("malformed.json:3:"), "{e}");
}

#[test]
fn unknown_fields_such_as_a_command_are_refused() {
    let e = graph::load(&data("bad/unknown_field.json"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("unknown field `command`"), "{e}");
}

/// Issue 23: an editor's `"$schema"` key is accepted (and other unknown keys still refused).
#[test]
fn a_schema_key_is_accepted() {
    let g = parse(
        r#"{"$schema": "../docs/graph.schema.json", "format": "cgnodes-graph", "version": 1,
            "nodes": {"a": {"type": "value_float", "params": {"value": 2}}}}"#,
    );
    assert_eq!(g.spec.schema.as_deref(), Some("../docs/graph.schema.json"));
    let e = graph::parse(
        r#"{"$scheme": "x", "format": "cgnodes-graph", "version": 1, "nodes": {}}"#,
        Path::new("inline.json"),
        Path::new("."),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("unknown field `$scheme`"), "{e}");
}

#[test]
fn unknown_target_and_missing_file() {
    let e = errors_of("bad_target.json");
    assert!(
        matches!(&e[0], GraphError::UnknownTarget { node, .. } if node == "b"),
        "{}",
        e[0]
    );
    let e = errors_of("missing_file.json");
    let msg = e[0].to_string();
    assert!(
        matches!(&e[0], GraphError::MissingFile { node, socket, .. } if node == "m" && socket == "path"),
        "{msg}"
    );
    assert!(msg.contains("no_such_mesh.obj"), "{msg}");
}

#[test]
fn every_error_is_reported_together() {
    let g = parse(
        r#"{"format":"cgnodes-graph","version":1,"nodes":{
        "a":{"type":"nope"},
        "b":{"type":"math","params":{"op":"zzz","q":1}},
        "c":{"type":"print","inputs":{"value":"missing.value"}}}}"#,
    );
    let e = validate(&g, &cgnodes::nodes::builtin_registry()).unwrap_err();
    assert!(e.len() >= 4, "{e:?}");
}

// ---------------------------------------------------------------- execution

#[test]
fn independent_slow_nodes_overlap_in_time() {
    let spans: Arc<Mutex<Vec<(String, Instant, Instant)>>> = Arc::default();
    let mut r = cgnodes::nodes::builtin_registry();
    let s = spans.clone();
    r.add(
        "sleepy",
        |b| {
            b.add_input::<f64>("ms").default(300.0);
            b.add_output::<f64>("value");
        },
        move |ctx| {
            let t0 = Instant::now();
            std::thread::sleep(Duration::from_millis(ctx.input::<f64>("ms")? as u64));
            s.lock()
                .unwrap()
                .push((ctx.node_id.to_string(), t0, Instant::now()));
            ctx.set_output("value", 1.0);
            Ok(())
        },
    );
    let g = parse(
        r#"{"format":"cgnodes-graph","version":1,"nodes":{
        "s1":{"type":"sleepy"}, "s2":{"type":"sleepy"},
        "sum":{"type":"math","inputs":{"a":"s1.value","b":"s2.value"}}},
        "outputs":["sum"]}"#,
    );
    let v = valid(&g, &r);
    let exec = Executor::new(Some(2), None).unwrap();
    let out = tempfile::tempdir().unwrap();
    let rep = exec.run(&v, &opts(out.path()), 0);
    assert!(rep.ok(), "{:?}", rep.errors());
    assert!(
        matches!(rep.output("sum", "value"), Some(cgnodes::types::Value::Float(x)) if *x == 2.0)
    );
    let sp = spans.lock().unwrap();
    assert_eq!(sp.len(), 2);
    let (a0, a1) = (sp[0].1, sp[0].2);
    let (b0, b1) = (sp[1].1, sp[1].2);
    assert!(a0 < b1 && b0 < a1, "the two sleeps ran one after the other");
}

#[test]
fn an_unused_branch_never_runs() {
    let counts: Arc<Mutex<HashMap<String, usize>>> = Arc::default();
    let r = counting_registry(counts.clone());
    let g = parse(
        r#"{"format":"cgnodes-graph","version":1,"nodes":{
        "used":{"type":"count_add","params":{"x":1}},
        "unused":{"type":"count_add","params":{"x":2}},
        "unused_child":{"type":"count_add","inputs":{"x":"unused.value"}},
        "w":{"type":"table_write","params":{"path":"v.csv"},"inputs":{"value":"used.value"}}}}"#,
    );
    let v = valid(&g, &r);
    let out = tempfile::tempdir().unwrap();
    let rep = Executor::new(None, None)
        .unwrap()
        .run(&v, &opts(out.path()), 0);
    assert!(rep.ok());
    let c = counts.lock().unwrap();
    assert_eq!(c.get("used"), Some(&1));
    assert_eq!(c.get("unused"), None);
    assert!(matches!(
        rep.node("unused_child").unwrap().status,
        NodeStatus::Skipped
    ));
    assert_eq!(
        std::fs::read_to_string(out.path().join("v.csv")).unwrap(),
        "value\n2\n"
    );
}

const CHAIN: &str = r#"{"format":"cgnodes-graph","version":1,"nodes":{
    "a":{"type":"count_add","params":{"x":1}},
    "b":{"type":"count_add","params":{"k":10},"inputs":{"x":"a.value"}},
    "c":{"type":"count_add","inputs":{"x":"b.value"}},
    "d":{"type":"count_add","params":{"x":5}},
    "wc":{"type":"table_write","params":{"path":"c.csv"},"inputs":{"value":"c.value"}},
    "wd":{"type":"table_write","params":{"path":"d.csv"},"inputs":{"value":"d.value"}}}}"#;

fn with_b_k(k: f64) -> Graph {
    let mut g = parse(CHAIN);
    cgnodes::cli::apply_sets(&mut g, &[format!("b.k={k}")]).unwrap();
    g
}

fn executed(rep: &RunReport) -> Vec<String> {
    let mut v: Vec<String> = rep.executed().iter().map(|s| s.to_string()).collect();
    v.sort();
    v
}

#[test]
fn a_changed_parameter_reruns_only_what_is_downstream_in_memory() {
    let counts: Arc<Mutex<HashMap<String, usize>>> = Arc::default();
    let r = counting_registry(counts.clone());
    let out = tempfile::tempdir().unwrap();
    let exec = Executor::new(None, None).unwrap();
    let rep = exec.run(&valid(&with_b_k(10.0), &r), &opts(out.path()), 0);
    assert_eq!(executed(&rep), ["a", "b", "c", "d", "wc", "wd"]);
    let rep = exec.run(&valid(&with_b_k(20.0), &r), &opts(out.path()), 0);
    assert_eq!(executed(&rep), ["b", "c", "wc"]);
    assert!(matches!(rep.node("a").unwrap().status, NodeStatus::Cached));
    assert_eq!(
        std::fs::read_to_string(out.path().join("c.csv")).unwrap(),
        "value\n23\n"
    );
    // Nothing changed: nothing runs.
    let rep = exec.run(&valid(&with_b_k(20.0), &r), &opts(out.path()), 0);
    assert!(executed(&rep).is_empty());
    let c = counts.lock().unwrap();
    assert_eq!((c["a"], c["b"], c["c"], c["d"]), (1, 2, 2, 1));
}

#[test]
fn a_changed_parameter_reruns_only_what_is_downstream_with_a_disk_cache() {
    let counts: Arc<Mutex<HashMap<String, usize>>> = Arc::default();
    let r = counting_registry(counts.clone());
    let out = tempfile::tempdir().unwrap();
    let cache = tempfile::tempdir().unwrap();
    // Each run is a fresh executor, as separate `cgnodes run --cache DIR` processes are.
    let run = |k: f64| {
        Executor::new(None, Some(cache.path())).unwrap().run(
            &valid(&with_b_k(k), &r),
            &opts(out.path()),
            0,
        )
    };
    assert_eq!(executed(&run(10.0)), ["a", "b", "c", "d", "wc", "wd"]);
    assert_eq!(executed(&run(20.0)), ["b", "c", "wc"]);
    assert!(executed(&run(20.0)).is_empty());
    // A writer whose file was deleted runs again.
    std::fs::remove_file(out.path().join("d.csv")).unwrap();
    assert_eq!(executed(&run(20.0)), ["wd"]);
    assert!(out.path().join("d.csv").exists());
}

#[test]
fn frames_keep_state_and_run_time_independent_nodes_once() {
    let counts: Arc<Mutex<HashMap<String, usize>>> = Arc::default();
    let r = counting_registry(counts.clone());
    let g = parse(
        r#"{"format":"cgnodes-graph","version":1,"nodes":{
        "x":{"type":"count_add","params":{"x":1,"k":1}},
        "acc":{"type":"accumulate","inputs":{"x":"x.value"}},
        "w":{"type":"table_write","params":{"path":"total_{frame:03}.csv"},"inputs":{"value":"acc.total"}}}}"#,
    );
    let v = valid(&g, &r);
    let out = tempfile::tempdir().unwrap();
    let exec = Executor::new(None, None).unwrap();
    for f in 1..=5 {
        let rep = exec.run(&v, &opts(out.path()), f);
        assert!(rep.ok(), "{:?}", rep.errors());
    }
    for f in 1..=5 {
        let t = std::fs::read_to_string(out.path().join(format!("total_{f:03}.csv"))).unwrap();
        assert_eq!(t, format!("value\n{}\n", 2 * f));
    }
    let c = counts.lock().unwrap();
    assert_eq!(c["x"], 1, "a node that does not depend on time runs once");
    assert_eq!(c["acc"], 5);
}

#[test]
fn a_failing_writer_leaves_no_partial_file_and_the_rest_still_runs() {
    let mut r = cgnodes::nodes::builtin_registry();
    r.add(
        "bad_writer",
        |b| {
            b.sink();
            b.add_input::<String>("path").file_out();
        },
        |ctx| {
            let p: String = ctx.input("path")?;
            let path = ctx.output_path("path", &p)?;
            ctx.write_with(&path, |w| {
                w.write_all(b"half of the data")?;
                Err(std::io::Error::other("disk on fire"))
            })
        },
    );
    let g = parse(
        r#"{"format":"cgnodes-graph","version":1,"nodes":{
        "bad":{"type":"bad_writer","params":{"path":"broken.obj"}},
        "v":{"type":"value_float","params":{"value":3}},
        "good":{"type":"table_write","params":{"path":"good.csv"},"inputs":{"value":"v.value"}}}}"#,
    );
    let v = valid(&g, &r);
    let out = tempfile::tempdir().unwrap();
    let rep = Executor::new(None, None)
        .unwrap()
        .run(&v, &opts(out.path()), 0);
    assert!(!rep.ok());
    let errs = rep.errors().join("\n");
    assert!(
        errs.contains("node 'bad' (bad_writer) failed [io]") && errs.contains("disk on fire"),
        "{errs}"
    );
    let mut files: Vec<_> = std::fs::read_dir(out.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    files.sort();
    // The CSV and its provenance sidecar (docs/provenance.md).
    assert_eq!(
        files,
        vec![
            std::ffi::OsString::from("good.csv"),
            std::ffi::OsString::from("good.csv.provenance.json")
        ]
    );
}

#[test]
fn downstream_of_a_failure_is_reported_as_blocked() {
    let g = parse(
        r#"{"format":"cgnodes-graph","version":1,"nodes":{
        "d":{"type":"math","params":{"a":1,"b":0,"op":"div"}},
        "m":{"type":"math","inputs":{"a":"d.value"}},
        "w":{"type":"table_write","params":{"path":"m.csv"},"inputs":{"value":"m.value"}}}}"#,
    );
    let v = valid(&g, &cgnodes::nodes::builtin_registry());
    let out = tempfile::tempdir().unwrap();
    let rep = Executor::new(None, None)
        .unwrap()
        .run(&v, &opts(out.path()), 0);
    assert!(
        matches!(&rep.node("d").unwrap().status, NodeStatus::Failed(e) if e.socket.as_deref() == Some("b"))
    );
    assert!(matches!(&rep.node("w").unwrap().status, NodeStatus::Blocked { by } if by == "d"));
    assert!(!out.path().join("m.csv").exists());
}

#[test]
fn a_panicking_node_becomes_an_error() {
    let mut r = cgnodes::nodes::builtin_registry();
    r.add(
        "explodes",
        |b| {
            b.add_output::<f64>("value");
        },
        |_ctx| -> Result<(), NodeError> { panic!("kaboom") },
    );
    let g = parse(
        r#"{"format":"cgnodes-graph","version":1,"nodes":{"e":{"type":"explodes"}},"outputs":["e"]}"#,
    );
    let rep = Executor::new(None, None)
        .unwrap()
        .run(&valid(&g, &r), &RunOptions::default(), 0);
    assert!(rep.errors()[0].contains("kaboom"), "{:?}", rep.errors());
}

#[test]
fn writes_outside_the_output_directory_are_refused() {
    for path in [
        "../escape.csv",
        "/tmp/cgnodes_escape_test.csv",
        "a/../../escape.csv",
    ] {
        let g = parse(&format!(
            r#"{{"format":"cgnodes-graph","version":1,"nodes":{{
            "v":{{"type":"value_float","params":{{"value":1}}}},
            "w":{{"type":"table_write","params":{{"path":"{path}"}},"inputs":{{"value":"v.value"}}}}}}}}"#
        ));
        let v = valid(&g, &cgnodes::nodes::builtin_registry());
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("out");
        let rep = Executor::new(None, None).unwrap().run(&v, &opts(&out), 0);
        let errs = rep.errors().join("\n");
        assert!(
            errs.contains("node 'w' (table_write)") && errs.contains("socket 'path'"),
            "{errs}"
        );
        assert!(errs.contains("--allow-write-anywhere"), "{errs}");
        assert!(!root.path().join("escape.csv").exists());
    }
    assert!(!Path::new("/tmp/cgnodes_escape_test.csv").exists());
}

#[test]
fn set_overrides_reach_the_node_and_are_type_checked() {
    let mut g = graph::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/graphs/arithmetic.json"
    )))
    .unwrap();
    cgnodes::cli::apply_sets(&mut g, &["radius.value=3".into()]).unwrap();
    let v = valid(&g, &cgnodes::nodes::builtin_registry());
    let out = tempfile::tempdir().unwrap();
    let rep = Executor::new(None, None)
        .unwrap()
        .run(&v, &opts(out.path()), 0);
    let area = match rep.output("pi_r2", "value") {
        Some(cgnodes::types::Value::Float(x)) => *x,
        other => panic!("{other:?}"),
    };
    assert!((area - 9.0 * std::f64::consts::PI).abs() < 1e-12);
    // A value of the wrong type is a validation error naming the socket.
    let mut g = graph::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/graphs/arithmetic.json"
    )))
    .unwrap();
    cgnodes::cli::apply_sets(&mut g, &["radius.value=big".into()]).unwrap();
    let e = validate(&g, &cgnodes::nodes::builtin_registry()).unwrap_err();
    assert!(
        e[0].to_string()
            .contains("node 'radius' (value_float): input 'value'"),
        "{}",
        e[0]
    );
    // Linked sockets and unknown nodes are refused.
    assert!(cgnodes::cli::apply_sets(&mut g, &["area.a=2".into()])
        .unwrap_err()
        .to_string()
        .contains("linked"));
    assert!(cgnodes::cli::apply_sets(&mut g, &["radios.value=2".into()])
        .unwrap_err()
        .to_string()
        .contains("did you mean 'radius'"));
}

// ---------------------------------------------------------------- the command line

fn cgnodes(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_cgnodes"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn cli_run_set_and_exit_codes() {
    let out = tempfile::tempdir().unwrap();
    let o = out.path().to_str().unwrap();
    let g = concat!(env!("CARGO_MANIFEST_DIR"), "/graphs/arithmetic.json");
    let r = cgnodes(&["run", g, "--out", o, "--set", "radius.value=1", "--quiet"]);
    assert_eq!(
        r.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    let csv = std::fs::read_to_string(out.path().join("circle_area.csv")).unwrap();
    assert!(csv.starts_with("value\n3.14159265358979"), "{csv}");
    let bad = data("bad/cycle.json");
    let r = cgnodes(&["validate", bad.to_str().unwrap()]);
    assert_eq!(r.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&r.stderr).contains("cycle: a -> b -> c -> a"));
    let r = cgnodes(&[
        "run",
        g,
        "--out",
        o,
        "--set",
        "area.op=div",
        "--set",
        "area.b=0",
    ]);
    assert_eq!(r.status.code(), Some(1), "a failing node exits 1");
    let r = cgnodes(&["run", g, "--frames", "5..2"]);
    assert_eq!(r.status.code(), Some(2));
    let r = cgnodes(&["describe", "math"]);
    assert!(String::from_utf8_lossy(&r.stdout).contains("one of add | sub"));
    let r = cgnodes(&["nodes", "--json"]);
    let j: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert!(j.as_array().unwrap().iter().any(|n| n["type"] == "math"));
    let r = cgnodes(&["dot", g]);
    assert!(String::from_utf8_lossy(&r.stdout).contains("\"radius\" -> \"area\""));
}

#[test]
fn cli_profile_json_and_target() {
    let out = tempfile::tempdir().unwrap();
    let prof = out.path().join("profile.json");
    let g = concat!(env!("CARGO_MANIFEST_DIR"), "/graphs/arithmetic.json");
    let r = cgnodes(&[
        "run",
        g,
        "--out",
        out.path().to_str().unwrap(),
        "--target",
        "area",
        "--quiet",
        "--profile-json",
        prof.to_str().unwrap(),
    ]);
    assert_eq!(r.status.code(), Some(0));
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(prof).unwrap()).unwrap();
    let nodes = j[0]["nodes"].as_array().unwrap();
    let status = |id: &str| nodes.iter().find(|n| n["id"] == id).unwrap()["status"].clone();
    assert_eq!(status("area"), "ran");
    assert_eq!(status("save"), "skipped");
    assert!(!out.path().join("circle_area.csv").exists());
}

#[test]
fn the_committed_schema_matches_the_code() {
    let committed = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/docs/graph.schema.json"
    ))
    .unwrap();
    let now =
        serde_json::to_string_pretty(&graph::typed_schema(&cgnodes::nodes::builtin_registry()))
            .unwrap();
    assert_eq!(
        committed.trim(),
        now.trim(),
        "run `cgnodes schema > docs/graph.schema.json` (the schema lists every node type)"
    );
}

// ---------------------------------------------------------------- wanted outputs

/// A registry with `pair`, a node with outputs `a` and `b` that computes only the wanted
/// ones and records, per run, which it computed.
fn pair_registry(log: Arc<Mutex<Vec<Vec<&'static str>>>>) -> Registry {
    let mut r = cgnodes::nodes::builtin_registry();
    r.add(
        "pair",
        |b| {
            b.add_input::<f64>("x").default(1.0);
            b.add_output::<f64>("a");
            b.add_output::<f64>("b");
        },
        move |ctx| {
            let x: f64 = ctx.input("x")?;
            let mut made = Vec::new();
            for (name, v) in [("a", x + 1.0), ("b", x + 2.0)] {
                if ctx.output_wanted(name) {
                    ctx.set_output(name, v);
                    made.push(name);
                }
            }
            log.lock().unwrap().push(made);
            Ok(())
        },
    );
    r
}

#[test]
fn nodes_compute_only_linked_or_requested_outputs() {
    let log = Arc::new(Mutex::new(Vec::new()));
    let r = pair_registry(log.clone());
    let g = parse(
        r#"{"format": "cgnodes-graph", "version": 1, "outputs": ["use"], "nodes": {
            "p": {"type": "pair", "params": {"x": 1.0}},
            "use": {"type": "math", "inputs": {"a": "p.a"}, "params": {"b": 10.0, "op": "add"}}
        }}"#,
    );
    let v = valid(&g, &r);
    let exec = Executor::new(Some(2), None).unwrap();
    let last = || log.lock().unwrap().last().cloned();
    // Only `a` is linked: `b` is neither computed nor reported, and that is no error.
    let r1 = exec.run(&v, &RunOptions::default(), 0);
    assert!(r1.ok(), "{:?}", r1.errors());
    assert_eq!(last(), Some(vec!["a"]));
    assert!(r1.output("p", "b").is_none());
    assert!(
        matches!(r1.output("use", "value"), Some(cgnodes::types::Value::Float(x)) if *x == 12.0)
    );
    // Reading `p.b` after the run: the cached entry skipped it, so `p` runs again; the new
    // entry keeps `a` too.
    let read_b = RunOptions {
        read_outputs: vec!["p.b".into()],
        ..Default::default()
    };
    let r2 = exec.run(&v, &read_b, 0);
    assert!(matches!(r2.node("p").unwrap().status, NodeStatus::Ran));
    assert_eq!(last(), Some(vec!["a", "b"]));
    assert!(matches!(r2.output("p", "b"), Some(cgnodes::types::Value::Float(x)) if *x == 3.0));
    let r3 = exec.run(&v, &read_b, 0);
    assert!(matches!(r3.node("p").unwrap().status, NodeStatus::Cached));
    // A target computes all its outputs; so does every node with `all_outputs`.
    let fresh = Executor::new(Some(2), None).unwrap();
    let target = RunOptions {
        targets: Some(vec!["p".into()]),
        ..Default::default()
    };
    fresh.run(&v, &target, 0);
    assert_eq!(last(), Some(vec!["a", "b"]));
    let fresh = Executor::new(Some(2), None).unwrap();
    let all = RunOptions {
        all_outputs: true,
        ..Default::default()
    };
    fresh.run(&v, &all, 0);
    assert_eq!(last(), Some(vec!["a", "b"]));
    assert_eq!(log.lock().unwrap().len(), 4);
}

/// Issue 23: a linked value is checked against the declared range and choices like a literal
/// (a linked 0 cells used to reach `mesh_grid`, a misspelt linked plane its fallback).
#[test]
fn linked_values_are_checked_against_ranges_and_choices() {
    let text = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
        "n": {"type": "value_int", "params": {"value": 0}},
        "p": {"type": "value_string", "params": {"value": "diagonal"}},
        "few": {"type": "mesh_grid", "inputs": {"cells_u": "n.value"}},
        "odd": {"type": "mesh_grid", "inputs": {"plane": "p.value"}},
        "ok": {"type": "mesh_grid", "params": {"cells_u": 2}}
      }, "outputs": ["few", "odd", "ok"]}"#;
    let dir = tempfile::tempdir().unwrap();
    let r = cgnodes::nodes::builtin_registry();
    let rep = crate::common::run_graph(text, &r, dir.path(), dir.path(), 1, 0..=0).remove(0);
    let failed = |id: &str| match &rep.node(id).unwrap().status {
        NodeStatus::Failed(e) => e.clone(),
        other => panic!("{id}: {other:?}"),
    };
    let e = failed("few");
    assert_eq!(e.socket.as_deref(), Some("cells_u"));
    assert!(e.message.contains("below the minimum 1"), "{}", e.message);
    let e = failed("odd");
    assert_eq!(e.socket.as_deref(), Some("plane"));
    assert!(
        e.message.contains("'diagonal' is not one of"),
        "{}",
        e.message
    );
    assert!(rep.output("ok", "mesh").is_some());
}
