//! Plugins: the example Python plugin against a direct computation, misbehaving plugins whose
//! failures stay contained, graphs that try to name a command; the Rust example crate in
//! `example_crate`.

use cgnodes::exec::{NodeStatus, RunReport};
use cgnodes::node::{ErrorKind, NodeError};
use cgnodes::plugin;
use cgnodes::registry::Registry;
use cgnodes::types::{Attribute, Domain, Image, Mesh, Points, Table, Value};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{pid_alive, root};

mod example_crate;

/// The test plugins' folder (`misbehave`).
pub(super) fn test_plugins() -> PathBuf {
    root().join("tests/data/plugins")
}

/// Built-in nodes plus the test plugin and the example plugin.
fn registry() -> Registry {
    let mut r = cgnodes::nodes::builtin_registry();
    for d in [
        test_plugins().join("misbehave"),
        root().join("plugins/laplacian_smooth"),
    ] {
        let w = plugin::register(&mut r, plugin::load(&d).unwrap());
        assert!(w.is_empty(), "{w:?}");
    }
    r
}

fn python_available() -> bool {
    Command::new("python3")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

fn numpy_available() -> bool {
    Command::new("python3")
        .args(["-c", "import numpy"])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// Runs graph `text` (relative paths resolve in `dir`) for `frames`; returns the reports.
fn run(
    text: &str,
    dir: &Path,
    out: &Path,
    frames: std::ops::RangeInclusive<i64>,
) -> Vec<RunReport> {
    crate::common::run_graph(text, &registry(), dir, out, 2, frames)
}

fn failure(r: &RunReport, id: &str) -> NodeError {
    match &r.node(id).unwrap().status {
        NodeStatus::Failed(e) => e.clone(),
        other => panic!("node '{id}' should have failed, status {other:?}"),
    }
}

/// Calls one plugin node directly with `inputs`.
fn call(
    node: &str,
    inputs: BTreeMap<String, Value>,
    timeout: f64,
) -> Result<plugin::CallResult, NodeError> {
    let p = plugin::load(&test_plugins().join("misbehave")).unwrap();
    let decl = p.node(node).unwrap();
    let runner = p.runner();
    plugin::call(&runner, decl, &inputs, 0, None, timeout)
}

fn quad_mesh() -> Mesh {
    // Two quads and a triangle, with per-corner UVs and a per-vertex attribute.
    let p = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.5],
        [2.0, 1.0, 0.0],
        [1.0, 2.0, 0.25],
    ];
    let mut m = Mesh::new(p, vec![4, 4, 3], vec![0, 1, 4, 3, 1, 2, 5, 4, 3, 4, 6]).unwrap();
    m.uvs = Some(Attribute {
        domain: Domain::Corner,
        values: (0..11)
            .map(|i| [i as f64 * 0.1, 1.0 - i as f64 * 0.05])
            .collect(),
    });
    m.attributes.insert(
        "heat".into(),
        cgnodes::types::AttributeData::Float(Attribute {
            domain: Domain::Vertex,
            values: vec![0.5, 1.5, 2.5, 3.5, 4.5, 5.5, 6.5],
        }),
    );
    m
}

#[test]
fn values_survive_the_round_trip() {
    if !python_available() {
        panic!("python3 is needed for the plugin tests");
    }
    let mesh = quad_mesh();
    let image = Image {
        width: 3,
        height: 2,
        pixels: (0..6)
            .map(|i| [i as f32, 0.5, -1.0, 0.25 * i as f32])
            .collect(),
    };
    let mut points = Points {
        dim: 2,
        positions: vec![[0.0, 1.0, 0.0], [2.0, 3.0, 0.0]],
        ..Default::default()
    };
    points.scalars.insert("density".into(), vec![1000.0, 998.5]);
    points
        .vectors
        .insert("velocity".into(), vec![[1.0, 0.0, 0.0], [0.0, -9.8, 0.0]]);
    let mut table = Table::from_row(&[("t", 0.5), ("energy", 2.0)]);
    table.meta.insert("stop_reason".into(), "converged".into());
    let camera = cgnodes::types::Camera::default();
    let mut inputs = BTreeMap::new();
    inputs.insert("x".into(), Value::Float(1.25));
    inputs.insert("n".into(), Value::Int(-7));
    inputs.insert("v".into(), Value::Vec3([0.5, 1.5, 2.5]));
    inputs.insert("s".into(), Value::String("ünïcode".into()));
    inputs.insert("xs".into(), Value::from(vec![1.0, 2.0, 3.0]));
    inputs.insert("mesh".into(), Value::from(mesh.clone()));
    inputs.insert("image".into(), Value::from(image.clone()));
    inputs.insert("points".into(), Value::from(points.clone()));
    inputs.insert("table".into(), Value::from(table.clone()));
    inputs.insert("camera".into(), Value::from(camera.clone()));
    let r = call("pl_echo", inputs, 30.0).unwrap();
    let o = &r.outputs;
    assert!(matches!(o["y"], Value::Float(y) if y == 2.5));
    assert!(matches!(o["n"], Value::Int(-7)));
    assert!(matches!(o["v"], Value::Vec3(v) if v == [0.5, 1.5, 2.5]));
    assert!(matches!(&o["s"], Value::String(s) if s == "ünïcode"));
    assert!(matches!(&o["xs"], Value::List(l) if l.len() == 3));
    let Value::Mesh(m) = &o["mesh"] else { panic!() };
    assert_eq!(m.positions, mesh.positions);
    assert_eq!(m.face_counts(), mesh.face_counts());
    assert_eq!(m.face_indices(), mesh.face_indices());
    assert_eq!(m.uvs, mesh.uvs);
    assert_eq!(m.attributes, mesh.attributes);
    let Value::Image(i) = &o["image"] else {
        panic!()
    };
    assert_eq!(**i, image);
    let Value::Points(p) = &o["points"] else {
        panic!()
    };
    assert_eq!(**p, points);
    let Value::Table(t) = &o["table"] else {
        panic!()
    };
    assert_eq!(**t, table);
    let Value::Camera(c) = &o["camera"] else {
        panic!()
    };
    assert_eq!(**c, camera);
    // The response's log, then stderr.
    assert_eq!(r.logs, ["echo ran", "echo: sent everything back"]);
}

/// Uniform Laplacian smoothing computed directly from the mesh's connectivity (Taubin 1995,
/// umbrella operator with uniform weights), the reference for the Python plugin.
fn smooth_reference(
    mesh: &Mesh,
    iterations: usize,
    lambda: f64,
    fix_boundary: bool,
) -> Vec<[f64; 3]> {
    let topo = mesh.topology();
    let n = mesh.positions.len();
    let free: Vec<bool> = (0..n)
        .map(|v| {
            let isolated = topo.neighbors(v).is_empty();
            let pinned = fix_boundary && topo.is_boundary_vertex(v);
            !isolated && !pinned
        })
        .collect();
    let mut p = mesh.positions.clone();
    for _ in 0..iterations {
        let prev = p.clone();
        for v in 0..n {
            if !free[v] {
                continue;
            }
            let nb = topo.neighbors(v);
            let mut avg = [0.0; 3];
            for &j in nb {
                for c in 0..3 {
                    avg[c] += prev[j as usize][c] / nb.len() as f64;
                }
            }
            for c in 0..3 {
                p[v][c] = prev[v][c] + lambda * (avg[c] - prev[v][c]);
            }
        }
    }
    p
}

#[test]
fn python_laplacian_smooth_matches_a_direct_computation() {
    if !numpy_available() {
        crate::common::skip_or_fail(
            "python_laplacian_smooth_matches_a_direct_computation",
            "python3 with numpy is not installed (python3 -m pip install numpy)",
        );
        return;
    }
    // The example graph as shipped, run with the plugin.
    let graph = root().join("plugins/laplacian_smooth/graph.json");
    let text = std::fs::read_to_string(&graph).unwrap();
    let out = tempfile::tempdir().unwrap();
    let r = run(&text, graph.parent().unwrap(), out.path(), 0..=0).remove(0);
    assert!(r.ok(), "{:?}", r.errors());
    assert!(out.path().join("camelhead_smooth.obj").exists());
    let Some(Value::Mesh(input)) = r.output("load", "mesh") else {
        panic!()
    };
    let Some(Value::Mesh(smoothed)) = r.output("smooth", "mesh") else {
        panic!()
    };
    let Some(Value::Float(moved)) = r.output("smooth", "max_displacement") else {
        panic!()
    };
    let want = smooth_reference(input, 20, 0.5, true);
    assert_eq!(smoothed.positions.len(), input.positions.len());
    let mut err: f64 = 0.0;
    let mut biggest: f64 = 0.0;
    for ((a, b), p0) in smoothed.positions.iter().zip(&want).zip(&input.positions) {
        err = err.max((0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max));
        biggest = biggest.max((0..3).map(|c| (b[c] - p0[c]).powi(2)).sum::<f64>().sqrt());
    }
    assert!(err < 1e-12, "plugin and reference differ by {err}");
    assert!(biggest > 1e-3, "smoothing moved nothing");
    assert!((moved - biggest).abs() < 1e-12, "{moved} vs {biggest}");
    assert_eq!(smoothed.face_indices(), input.face_indices());
    // camelhead is open: its boundary stays where it was.
    let topo = input.topology();
    let mut on_boundary = 0;
    for v in 0..input.positions.len() {
        if topo.is_boundary_vertex(v) {
            on_boundary += 1;
            assert_eq!(smoothed.positions[v], input.positions[v]);
        }
    }
    assert!(on_boundary > 0);
    // Without the boundary fixed, on a small mesh, straight through `plugin::call`.
    let mesh = quad_mesh();
    let p = plugin::load(&root().join("plugins/laplacian_smooth")).unwrap();
    let runner = p.runner();
    let mut inputs = BTreeMap::new();
    inputs.insert("mesh".into(), Value::from(mesh.clone()));
    inputs.insert("iterations".into(), Value::Int(3));
    inputs.insert("lambda".into(), Value::Float(0.3));
    inputs.insert("fix_boundary".into(), Value::Bool(false));
    let res = plugin::call(&runner, &p.nodes[0], &inputs, 0, None, 60.0).unwrap();
    let Value::Mesh(m) = &res.outputs["mesh"] else {
        panic!()
    };
    let want = smooth_reference(&mesh, 3, 0.3, false);
    assert_eq!(m.positions.len(), want.len());
    for (a, b) in m.positions.iter().zip(&want) {
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() < 1e-14);
        }
    }
    // The base mesh's UVs and attributes come through untouched.
    assert_eq!(m.uvs, mesh.uvs);
    assert_eq!(m.attributes, mesh.attributes);
}

#[test]
fn a_crashing_plugin_fails_its_node_only() {
    let text = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
        "crash": {"type": "pl_crash", "params": {"x": 0}},
        "after": {"type": "math", "inputs": {"a": "crash.y"}},
        "echo": {"type": "pl_echo", "params": {"x": 4}},
        "show": {"type": "print", "inputs": {"value": "echo.y"}},
        "show2": {"type": "print", "inputs": {"value": "after.value"}}
    }}"#;
    let out = tempfile::tempdir().unwrap();
    let r = run(text, root(), out.path(), 0..=0).remove(0);
    let e = failure(&r, "crash");
    assert_eq!(e.kind, ErrorKind::Plugin);
    assert!(e.message.contains("exited with status 1"), "{}", e.message);
    // The tail of stderr: the plugin's own line and Python's traceback.
    assert!(
        e.message.contains("about to divide by zero"),
        "{}",
        e.message
    );
    assert!(e.message.contains("ZeroDivisionError"), "{}", e.message);
    assert!(matches!(
        r.node("after").unwrap().status,
        NodeStatus::Blocked { .. }
    ));
    // The independent branch ran.
    assert!(matches!(r.output("echo", "y"), Some(Value::Float(y)) if *y == 8.0));
    assert!(matches!(r.node("show").unwrap().status, NodeStatus::Ran));
}

/// The plugin prints a line, starts a child, writes the child's pid to `pidfile` (the marker
/// that it reached its sleep) and sleeps for an hour; the runtime must kill it and its child at
/// the timeout. On a loaded machine Python may not reach the marker within a short timeout, so
/// the run is repeated with longer timeouts until it does; the child check always runs.
#[test]
fn a_hanging_plugin_is_killed_at_its_timeout() {
    for timeout in [4u32, 16, 64] {
        let tmp = tempfile::tempdir().unwrap();
        let pidfile = tmp.path().join("child.pid");
        let text = format!(
            r#"{{"format": "cgnodes-graph", "version": 1, "nodes": {{
            "hang": {{"type": "pl_hang", "params": {{"timeout": {timeout}.0, "pidfile": {:?}}}}},
            "show": {{"type": "print", "inputs": {{"value": "hang.y"}}}},
            "ok": {{"type": "pl_echo", "params": {{"x": 1}}}},
            "show_ok": {{"type": "print", "inputs": {{"value": "ok.y"}}}}
        }}}}"#,
            pidfile.to_str().unwrap()
        );
        let t0 = std::time::Instant::now();
        let r = run(&text, root(), tmp.path(), 0..=0).remove(0);
        // The plugin sleeps for an hour; the run ends because the process was killed.
        assert!(t0.elapsed().as_secs() < 600);
        let e = failure(&r, "hang");
        assert_eq!(e.kind, ErrorKind::Plugin);
        let want = format!("timed out after {timeout} s");
        assert!(e.message.contains(&want), "{}", e.message);
        assert!(matches!(r.output("ok", "y"), Some(Value::Float(y)) if *y == 2.0));
        // No complete pid yet: killed before it reached the sleep; try a longer timeout.
        let Some(pid) = std::fs::read_to_string(&pidfile)
            .ok()
            .and_then(|s| s.trim().parse::<u32>().ok())
        else {
            eprintln!("timeout {timeout} s: the plugin did not reach its sleep; retrying longer");
            continue;
        };
        assert!(e.message.contains("hanging now"), "{}", e.message);
        // The process the plugin started was killed with it.
        let mut alive = pid_alive(pid);
        for _ in 0..100 {
            if !alive {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
            alive = pid_alive(pid);
        }
        assert!(!alive, "the plugin's child {pid} outlived the timeout");
        return;
    }
    panic!("the hanging plugin never reached its sleep, even with a 64 s timeout");
}

#[test]
fn wrong_responses_become_plugin_errors() {
    let mut with_mesh = BTreeMap::new();
    with_mesh.insert("mesh".to_string(), Value::from(quad_mesh()));
    let cases: [(&str, BTreeMap<String, Value>, &str); 7] = [
        (
            "pl_wrong_type",
            BTreeMap::new(),
            "output 'count' (int): expected an integer, got \"three\"",
        ),
        (
            "pl_wrong_shape",
            with_mesh.clone(),
            "mesh 'positions' should have shape (N, 3), got (3,)",
        ),
        ("pl_escape", with_mesh, "outside the call folder"),
        (
            "pl_bad_json",
            BTreeMap::new(),
            "not JSON (log lines go to stderr): \"this is not JSON\\n\"",
        ),
        (
            "pl_bad_protocol",
            BTreeMap::new(),
            "\"protocol\": 1, got 99",
        ),
        (
            "pl_missing_output",
            BTreeMap::new(),
            "returned no output 'y'",
        ),
        (
            "pl_reported_error",
            BTreeMap::new(),
            "reported an error: the input mesh must be closed",
        ),
    ];
    for (node, inputs, want) in cases {
        let e = call(node, inputs, 30.0)
            .err()
            .unwrap_or_else(|| panic!("{node} should fail"));
        assert_eq!(e.kind, ErrorKind::Plugin, "{node}");
        assert!(
            e.message.starts_with("plugin 'misbehave': "),
            "{node}: {}",
            e.message
        );
        assert!(e.message.contains(want), "{node}: {}", e.message);
    }
    let e = call("pl_reported_error", BTreeMap::new(), 30.0).unwrap_err();
    assert!(e.message.contains("checking the input"), "{}", e.message);
}

#[test]
fn stateful_plugins_keep_state_and_file_outputs_land_in_the_output_folder() {
    let text = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
        "count": {"type": "pl_counter"},
        "show": {"type": "print", "inputs": {"value": "count.count"}},
        "w": {"type": "pl_write", "params": {"path": "sub/hello_{frame}.txt", "text": "hé"}},
        "show_w": {"type": "print", "inputs": {"value": "w.bytes"}}
    }}"#;
    let out = tempfile::tempdir().unwrap();
    let reports = run(text, root(), out.path(), 0..=2);
    for (k, r) in reports.iter().enumerate() {
        assert!(r.ok(), "{:?}", r.errors());
        assert!(matches!(r.output("count", "count"), Some(Value::Int(c)) if *c == k as i64 + 1));
        assert!(matches!(r.output("count", "frame"), Some(Value::Int(f)) if *f == k as i64));
    }
    let f = out.path().join("sub/hello_0.txt");
    assert_eq!(std::fs::read_to_string(&f).unwrap(), "hé");
    assert!(matches!(
        reports[0].output("w", "bytes"),
        Some(Value::Int(3))
    ));
    assert_eq!(reports[0].node("w").unwrap().written, [f]);
}

#[test]
fn a_graph_cannot_name_a_command() {
    let tmp = tempfile::tempdir().unwrap();
    let marker = tmp.path().join("ran");
    let cmd = format!("touch {}", marker.display());
    let attempts = [
        // A command next to a node's type.
        format!(
            r#"{{"format": "cgnodes-graph", "version": 1, "nodes": {{
            "x": {{"type": "pl_echo", "command": {cmd:?}}}}}}}"#
        ),
        format!(
            r#"{{"format": "cgnodes-graph", "version": 1, "nodes": {{
            "x": {{"type": "pl_echo", "command": ["sh", "-c", {cmd:?}]}}}}}}"#
        ),
        // A plugin folder or manifest named by the graph.
        format!(
            r#"{{"format": "cgnodes-graph", "version": 1, "plugins": [{:?}],
            "nodes": {{"x": {{"type": "pl_echo"}}}}}}"#,
            tmp.path().display().to_string()
        ),
        format!(
            r#"{{"format": "cgnodes-graph", "version": 1, "nodes": {{
            "x": {{"type": "pl_echo", "plugin": {{"command": [{cmd:?}]}}}}}}}}"#
        ),
    ];
    for text in &attempts {
        let e = cgnodes::graph::parse(text, Path::new("evil.json"), tmp.path())
            .expect_err("a graph naming a command must be refused at load time");
        assert!(e.to_string().contains("unknown field"), "{e}");
    }
    // As a parameter of a plugin node it is an unknown socket, refused before anything runs.
    let text = format!(
        r#"{{"format": "cgnodes-graph", "version": 1, "nodes": {{
        "x": {{"type": "pl_echo", "params": {{"command": {cmd:?}}}}}}}}}"#
    );
    let g = cgnodes::graph::parse(&text, Path::new("evil.json"), tmp.path()).unwrap();
    let errs = cgnodes::validate::validate(&g, &registry()).unwrap_err();
    assert!(
        errs.iter()
            .any(|e| e.to_string().contains("no input socket 'command'")),
        "{errs:?}"
    );
    // The same refusal through the command line, which exits before running anything.
    let evil = tmp.path().join("evil.json");
    std::fs::write(&evil, &attempts[0]).unwrap();
    if let Some(bin) = example_crate::example_binary() {
        let o = Command::new(bin)
            .args(["run", evil.to_str().unwrap(), "--plugins"])
            .arg(test_plugins())
            .arg("--out")
            .arg(tmp.path().join("out"))
            .output()
            .unwrap();
        assert_eq!(
            o.status.code(),
            Some(3),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    assert!(!marker.exists(), "a command named in a graph was executed");
}
