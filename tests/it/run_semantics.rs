//! Semantics of `cgnodes run`, `validate` and `dot` that a hostile or careless user meets
//! (issue 23): frames after a failed simulation, unused branches with problems, the options
//! the graph commands share, and Ctrl-C during a plugin call.

use std::path::Path;
use std::process::{Command, Output};

/// Runs the `cgnodes` binary with `args` in `cwd`.
fn cgnodes(cwd: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cgnodes"))
        .current_dir(cwd)
        .env("CI", "1")
        .args(args)
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A one-triangle OBJ.
const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

#[test]
fn validate_and_dot_take_assets_like_run() {
    let d = tempfile::tempdir().unwrap();
    let assets = d.path().join("assets");
    std::fs::create_dir(&assets).unwrap();
    std::fs::write(assets.join("tri.obj"), TRIANGLE).unwrap();
    let graph = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
        "m": {"type": "mesh_load", "params": {"path": "tri.obj"}},
        "s": {"type": "mesh_save", "inputs": {"mesh": "m.mesh"}, "params": {"path": "t.obj"}}
    }}"#;
    std::fs::write(d.path().join("g.json"), graph).unwrap();
    // Without the asset folder the file is missing: exit code 3, naming the node.
    let o = cgnodes(d.path(), &["validate", "g.json"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("node 'm'"), "{}", stderr(&o));
    let o = cgnodes(d.path(), &["dot", "g.json"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    // With it, all three commands accept the graph.
    let o = cgnodes(d.path(), &["validate", "g.json", "--assets", "assets"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("ok (2 nodes)"));
    let o = cgnodes(d.path(), &["dot", "--assets", "assets", "g.json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("\"m\" -> \"s\""));
    let o = cgnodes(
        d.path(),
        &["run", "g.json", "--assets", "assets", "--out", "out", "-q"],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(d.path().join("out/t.obj").exists());
    // `--set` and `--f3d-aliases` are shared too: a bad aliases file is a usage error.
    let o = cgnodes(
        d.path(),
        &["validate", "g.json", "--set", "m.path=\"assets/tri.obj\""],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = cgnodes(d.path(), &["dot", "g.json", "--f3d-aliases", "nope.json"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}
