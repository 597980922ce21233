//! Issue 23, nodes: linked strings outside a socket's choices and linked numbers outside its
//! range are refused before the node runs, naming node, type and socket; buffers sized from
//! parameters are checked against the memory limit (`--max-memory`) with the size stated; and
//! `compare_series` does not quote files outside the run's folders.

use crate::common::{stand_in, stand_in_nodes};
use cgnodes::exec::{Executor, NodeStatus, RunOptions, RunReport};
use cgnodes::node::{ErrorKind, FileEnv, NodeError};
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

/// Runs graph `text` (as a file in `dir`) for frame 0 with the memory limit `max_memory`.
fn run(text: &str, dir: &Path, max_memory: Option<u64>) -> RunReport {
    let r = cgnodes::nodes::builtin_registry();
    let g = cgnodes::graph::parse(text, &dir.join("test.json"), dir).unwrap();
    let valid = cgnodes::validate::validate(&g, &r).unwrap_or_else(|e| panic!("{}", e[0]));
    let exec = Executor::new(Some(2), None).unwrap();
    let opts = RunOptions {
        files: FileEnv {
            graph_dir: dir.to_path_buf(),
            out_dir: dir.join("out"),
            ..Default::default()
        },
        max_memory,
        ..Default::default()
    };
    exec.run(&valid, &opts, 0)
}

/// The error of node `id`, which must have failed.
fn failure(rep: &RunReport, id: &str) -> NodeError {
    match &rep.node(id).unwrap().status {
        NodeStatus::Failed(e) => e.clone(),
        other => panic!("{id}: {other:?}"),
    }
}

/// The line of `rep.errors()` about node `id`.
fn error_line(rep: &RunReport, id: &str) -> String {
    let tag = format!("node '{id}' (");
    rep.errors()
        .into_iter()
        .find(|l| l.contains(&tag))
        .unwrap_or_else(|| panic!("no error for {id}: {:?}", rep.errors()))
}

/// Every choice socket of every built-in node that can be fed here gets a misspelt linked
/// string: each run fails before the node executes, with the literal's message, and the
/// report line names node, type and socket. The sockets the issue found falling back to a
/// default silently are among them.
#[test]
fn misspelt_linked_strings_are_refused_on_every_choice_socket() {
    let registry = cgnodes::nodes::builtin_registry();
    let mut nodes = stand_in_nodes();
    nodes["bad"] = serde_json::json!({"type": "value_string", "params": {"value": "bogus"}});
    let mut tested = BTreeMap::new();
    let mut skipped = Vec::new();
    for decl in registry.iter() {
        for s in decl.inputs.iter().filter(|s| s.choices.is_some()) {
            let mut inputs = serde_json::Map::new();
            inputs.insert(s.name.clone(), "bad.value".into());
            let mut feedable = true;
            for o in &decl.inputs {
                if o.name == s.name || o.optional || o.default.is_some() {
                    continue;
                }
                match stand_in(&o.ty) {
                    Some(p) => {
                        inputs.insert(o.name.clone(), p.into());
                    }
                    None => feedable = false,
                }
            }
            if !feedable {
                skipped.push(format!("{}.{}", decl.type_name, s.name));
                continue;
            }
            let id = format!("t_{}_{}", decl.type_name, s.name);
            nodes[&id] = serde_json::json!({"type": decl.type_name, "inputs": inputs});
            tested.insert(id, (decl.type_name.clone(), s.name.clone()));
        }
    }
    for (ty, socket) in [
        ("sph_fluid", "solver"),
        ("sph_fluid", "boundary"),
        ("mass_spring", "gravity_axis"),
        ("render_raster", "texture_wrap"),
        ("render_raster", "antialiasing"),
        ("material", "kind"),
        ("camera", "fov_axis"),
    ] {
        assert!(
            tested.contains_key(&format!("t_{ty}_{socket}")),
            "{ty}.{socket} not tested (skipped: {skipped:?})"
        );
    }
    assert!(
        tested.len() >= 20,
        "{} tested, skipped {skipped:?}",
        tested.len()
    );
    let outputs: Vec<&String> = tested.keys().collect();
    let text = serde_json::json!({"format": "cgnodes-graph", "version": 1,
        "nodes": nodes, "outputs": outputs})
    .to_string();
    let dir = tempfile::tempdir().unwrap();
    let rep = run(&text, dir.path(), None);
    for (id, (ty, socket)) in &tested {
        let e = failure(&rep, id);
        assert_eq!(e.kind, ErrorKind::InvalidInput, "{id}: {e}");
        assert_eq!(e.socket.as_deref(), Some(socket.as_str()), "{id}: {e}");
        assert!(e.message.contains("'bogus' is not one of"), "{id}: {e}");
        let line = error_line(&rep, id);
        assert!(
            line.contains(&format!("node '{id}' ({ty})"))
                && line.contains(&format!("socket '{socket}'")),
            "{line}"
        );
    }
}

/// Linked numbers outside the declared range are refused before the node runs (a linked
/// dimension of 4 used to panic in sph_fluid, a negative image_width to wrap to 4e9, huge
/// cells to abort mesh_grid on allocation).
#[test]
fn out_of_range_linked_numbers_are_refused_not_crashed_on() {
    let text = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
        "four": {"type": "value_int", "params": {"value": 4}},
        "neg": {"type": "value_int", "params": {"value": -5}},
        "huge": {"type": "value_int", "params": {"value": 3000000000}},
        "dim": {"type": "sph_fluid", "inputs": {"dimension": "four.value"}},
        "img": {"type": "sph_fluid", "inputs": {"image_width": "neg.value"}},
        "gu": {"type": "mesh_grid", "inputs": {"cells_u": "huge.value"}},
        "gv": {"type": "mesh_grid", "inputs": {"cells_v": "huge.value"}}
      }, "outputs": ["dim", "img", "gu", "gv"]}"#;
    let dir = tempfile::tempdir().unwrap();
    let rep = run(text, dir.path(), None);
    for (id, socket, want) in [
        ("dim", "dimension", "4 is above the maximum 3"),
        ("img", "image_width", "-5 is below the minimum 8"),
        ("gu", "cells_u", "3000000000 is above the maximum 4096"),
        ("gv", "cells_v", "3000000000 is above the maximum 4096"),
    ] {
        let e = failure(&rep, id);
        assert_eq!(e.kind, ErrorKind::InvalidInput, "{id}: {e}");
        assert_eq!(e.socket.as_deref(), Some(socket), "{id}: {e}");
        assert!(e.message.contains(want), "{id}: {e}");
        assert!(error_line(&rep, id).contains(&format!("socket '{socket}'")));
    }
}

/// Buffers sized from parameters are checked against the memory limit before they are
/// allocated: a 16384 x 16384 render (linked size) is refused with its size by both tracers
/// and the rasterizer, a particle block by sph_fluid; under the default limit a small render
/// runs.
#[test]
fn renders_and_particle_blocks_over_the_memory_limit_are_refused_with_their_size() {
    let text = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
        "side": {"type": "value_int", "params": {"value": 16384}},
        "grid": {"type": "mesh_grid", "params": {"cells_u": 2, "cells_v": 2}},
        "cam": {"type": "camera", "inputs": {"width": "side.value", "height": "side.value"}},
        "sc": {"type": "scene", "inputs": {"meshes": "grid.mesh", "camera": "cam.camera"}},
        "path": {"type": "render_path", "inputs": {"scene": "sc.scene"}, "params": {"spp": 1}},
        "whitted": {"type": "render_whitted", "inputs": {"scene": "sc.scene"}},
        "raster": {"type": "render_raster", "inputs": {"scene": "sc.scene"}},
        "r": {"type": "value_float", "params": {"value": 0.0001}},
        "fluid": {"type": "sph_fluid", "inputs": {"particle_radius": "r.value"}},
        "small_cam": {"type": "camera", "params": {"width": 8, "height": 8}},
        "small": {"type": "render_path", "inputs": {"scene": "grid.mesh", "camera": "small_cam.camera"},
                  "params": {"spp": 1}}
      }, "outputs": ["path", "whitted", "raster", "fluid", "small"]}"#;
    let dir = tempfile::tempdir().unwrap();
    let rep = run(text, dir.path(), Some(8_000_000_000));
    for (id, socket, want) in [
        (
            "path",
            "camera",
            "a 16384x16384 image needs 27.9 GB, over the 8 GB limit",
        ),
        (
            "whitted",
            "camera",
            "a 16384x16384 image needs 8.59 GB, over the 8 GB limit",
        ),
        (
            "raster",
            "camera",
            "a 16384x16384 image with 4 samples per pixel needs 25.8 GB, over the 8 GB limit",
        ),
        ("fluid", "particle_radius", "e10 fluid and"),
    ] {
        let e = failure(&rep, id);
        assert_eq!(e.kind, ErrorKind::InvalidInput, "{id}: {e}");
        assert_eq!(e.socket.as_deref(), Some(socket), "{id}: {e}");
        assert!(e.message.contains(want), "{id}: {e}");
        assert!(
            e.message.contains("(--max-memory or CGNODES_MAX_MEMORY)"),
            "{id}: {e}"
        );
    }
    assert!(matches!(rep.node("small").unwrap().status, NodeStatus::Ran));
    // The default limit is half the physical memory unless the environment sets one.
    if std::env::var_os(cgnodes::node::MAX_MEMORY_ENV).is_none() {
        let half = cgnodes::node::physical_memory().map_or(8 << 30, |m| m / 2);
        assert_eq!(RunOptions::default().memory_limit(), half);
    }
}

/// Writes `text` as `g.json` in a fresh folder and runs `cgnodes ARGS` on it there, with
/// `env` set; returns (exit code, stdout, stderr) and the folder.
fn cli(text: &str, args: &[&str], env: &[(&str, &str)]) -> (i32, String, String) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("g.json"), text).unwrap();
    let mut c = Command::new(env!("CARGO_BIN_EXE_cgnodes"));
    c.current_dir(dir.path())
        .args(args)
        .env_remove(cgnodes::node::MAX_MEMORY_ENV);
    for (k, v) in env {
        c.env(k, v);
    }
    let o = c.output().unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into(),
        String::from_utf8_lossy(&o.stderr).into(),
    )
}

/// `--max-memory` (and CGNODES_MAX_MEMORY) lower the limit: a 300 x 300 grid, fine by
/// default, is refused with its size under 1 MB, by `run` and by `sweep`.
#[test]
fn max_memory_option_lowers_the_limit_for_run_and_sweep() {
    let text = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
        "g": {"type": "mesh_grid", "params": {"cells_u": 300, "cells_v": 300}},
        "info": {"type": "mesh_info", "inputs": {"mesh": "g.mesh"}}
      }, "outputs": ["info"]}"#;
    let want = "a 300x300 grid needs 7.93 MB, over the 1 MB limit";
    let (code, _, err) = cli(text, &["run", "g.json", "--out", "out"], &[]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = cli(
        text,
        &["run", "g.json", "--out", "out", "--max-memory", "1M"],
        &[],
    );
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("node 'g' (mesh_grid) failed") && err.contains(want),
        "{err}"
    );
    let (code, _, err) = cli(
        text,
        &["run", "g.json", "--out", "out"],
        &[("CGNODES_MAX_MEMORY", "1M")],
    );
    assert_eq!(code, 1, "{err}");
    assert!(err.contains(want), "{err}");
    let (code, _, err) = cli(text, &["run", "g.json", "--max-memory", "12Q"], &[]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("'12Q' is not a size"), "{err}");
    let (code, out, err) = cli(
        text,
        &[
            "sweep",
            "g.json",
            "--vary",
            "g.cells_v=300",
            "--measure",
            "info.table:vertices",
            "--max-memory",
            "1M",
        ],
        &[],
    );
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("1 runs, 1 failed"), "{err}");
    assert!(out.contains(want), "{out}");
}

/// compare_series quotes an unrecognised header only for files in the run's folders: a
/// reference outside them fails without its first line in the report or on stderr.
#[test]
fn compare_series_does_not_quote_files_outside_the_run_folders() {
    let root = tempfile::tempdir().unwrap();
    let (gdir, outside) = (root.path().join("graph"), root.path().join("outside"));
    std::fs::create_dir_all(&gdir).unwrap();
    std::fs::create_dir_all(&outside).unwrap();
    let secret = "TOP-SECRET-LINE,hunter2";
    std::fs::write(outside.join("secret.csv"), format!("{secret}\n1,2\n")).unwrap();
    std::fs::write(gdir.join("mine.csv"), format!("{secret}\n1,2\n")).unwrap();
    let graph = |reference: &Path| {
        serde_json::json!({"format": "cgnodes-graph", "version": 1, "nodes": {
            "grid": {"type": "mesh_grid", "params": {"cells_u": 2, "cells_v": 2}},
            "info": {"type": "mesh_info", "inputs": {"mesh": "grid.mesh"}},
            "cmp": {"type": "compare_series", "inputs": {"series": "info.table"},
                    "params": {"reference": reference.to_str().unwrap()}}
          }, "outputs": ["cmp"]})
        .to_string()
    };
    let rep = run(&graph(&outside.join("secret.csv")), &gdir, None);
    let e = failure(&rep, "cmp");
    assert_eq!(e.socket.as_deref(), Some("reference"));
    assert!(e.message.contains("its content is not shown"), "{e}");
    assert!(!e.message.contains("TOP-SECRET"), "{e}");
    assert!(rep.errors().iter().all(|l| !l.contains("TOP-SECRET")));
    // Through the command line, nothing of it reaches stdout or stderr either.
    let text = graph(&outside.join("secret.csv"));
    let (code, out, err) = cli(&text, &["run", "g.json", "--out", "out"], &[]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("node 'cmp' (compare_series) failed"), "{err}");
    assert!(!out.contains("TOP-SECRET") && !err.contains("TOP-SECRET"));
    // A file in the graph's own folder is still quoted, to help fix its header.
    let rep = run(&graph(&gdir.join("mine.csv")), &gdir, None);
    let e = failure(&rep, "cmp");
    assert!(e.message.contains("TOP-SECRET-LINE, hunter2"), "{e}");
}
