//! Helpers every test module uses: where the project's files are, and running a graph.

use cgnodes::exec::{Executor, RunOptions, RunReport};
use cgnodes::node::{ExecContext, FileEnv};
use cgnodes::registry::Registry;
use cgnodes::types::Value;
use std::collections::BTreeMap;
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};

/// Serializes the tests that paste with `poisson_blend` in this process: its caches are
/// process-wide (four mask shapes' factors, a new shape's warm start in one shared slot), and
/// a test pasting other shapes beside one that checks them could evict what it checks.
pub fn poisson_lock() -> std::sync::MutexGuard<'static, ()> {
    static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

/// The project root (assets, graphs, tests/data are below it).
pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A path below the project root.
pub fn asset(rel: &str) -> PathBuf {
    root().join(rel)
}

/// Parses graph `text` as if it were a file in `dir`, validates it against `registry` (a
/// failure panics with every error), and runs `frames` on `threads` threads, writing to `out`.
pub fn run_graph(
    text: &str,
    registry: &Registry,
    dir: &Path,
    out: &Path,
    threads: usize,
    frames: RangeInclusive<i64>,
) -> Vec<RunReport> {
    let g = cgnodes::graph::parse(text, &dir.join("test.json"), dir).unwrap();
    let valid = cgnodes::validate::validate(&g, registry).unwrap_or_else(|e| {
        panic!(
            "{}",
            e.iter()
                .map(|e| e.to_string())
                .collect::<Vec<_>>()
                .join("\n")
        )
    });
    let exec = Executor::new(Some(threads), None).unwrap();
    let opts = RunOptions {
        files: FileEnv {
            graph_dir: dir.to_path_buf(),
            out_dir: out.to_path_buf(),
            ..Default::default()
        },
        ..Default::default()
    };
    frames.map(|f| exec.run(&valid, &opts, f)).collect()
}

/// Whether the tests run on CI (`CI` set and not `0`/`false`, as `.ci/run` does). There a test
/// that needs an optional tool (Python with numpy, a built example binary) fails instead of
/// skipping, so a missing tool cannot turn a check into a silent pass.
pub fn on_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "0" && v != "false")
}

/// Reports that `test` cannot run because `why`: a panic on CI (see `on_ci`), a `SKIPPED` line
/// on stderr otherwise. The caller returns after it.
pub fn skip_or_fail(test: &str, why: &str) {
    let msg = format!("{test}: {why}");
    if on_ci() {
        panic!("{msg} (CI is set, so a missing tool is an error, not a skip)");
    }
    eprintln!("SKIPPED {msg}");
}

/// Whether process `pid` is running, from /proc: a killed child that nobody reaped yet is a
/// zombie ('Z') and does not count.
pub fn pid_alive(pid: u32) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Err(_) => false,
        Ok(s) => s
            .rsplit_once(')')
            .and_then(|(_, rest)| rest.split_whitespace().next())
            .is_some_and(|state| state != "Z" && state != "X"),
    }
}

/// Outputs of a node run alone, and its log lines.
pub type NodeOutputs = (BTreeMap<String, Value>, Vec<String>);

/// Runs built-in node `name` outside a graph, with `files` for its paths: its outputs and
/// log lines, or the error text.
pub fn run_node(
    name: &str,
    inputs: Vec<(&str, Value)>,
    files: &FileEnv,
) -> Result<NodeOutputs, String> {
    let r = cgnodes::nodes::builtin_registry();
    let decl = r.get(name).unwrap();
    let mut state = None;
    let ins: BTreeMap<String, Value> = inputs
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
    decl.check_inputs(&ins).map_err(|e| e.to_string())?;
    let mut ctx = ExecContext::standalone(decl, ins, &mut state, files, 0);
    (decl.exec.as_ref().unwrap())(&mut ctx).map_err(|e| e.to_string())?;
    let logs = ctx.logs().to_vec();
    Ok((ctx.take_outputs(), logs))
}

/// Small upstream nodes standing in for the inputs of a node under test (`stand_in`): a
/// 2x2 grid, its info table, an 8x8 camera, a material, a light, a UV image, a 2-D fluid and
/// constants.
pub fn stand_in_nodes() -> serde_json::Value {
    serde_json::json!({
        "grid": {"type": "mesh_grid", "params": {"cells_u": 2, "cells_v": 2}},
        "plane": {"type": "mesh_plane"},
        "info": {"type": "mesh_info", "inputs": {"mesh": "grid.mesh"}},
        "cam": {"type": "camera", "params": {"width": 8, "height": 8}},
        "mat": {"type": "material"},
        "light": {"type": "light_point"},
        "uvimg": {"type": "render_uv", "inputs": {"mesh": "plane.mesh"}, "params": {"size": 16}},
        "fluid": {"type": "sph_fluid", "params": {"dimension": 2}},
        "name": {"type": "value_string", "params": {"value": "x.ply"}},
        "one": {"type": "value_int", "params": {"value": 1}},
        "onef": {"type": "value_float", "params": {"value": 1.0}}
    })
}

/// The output of `stand_in_nodes` that feeds an input of type `ty` (its value does not
/// matter to the test), if one does.
pub fn stand_in(ty: &cgnodes::types::SocketType) -> Option<&'static str> {
    use cgnodes::types::SocketType as T;
    Some(match ty {
        T::Mesh | T::Scene => "grid.mesh",
        T::List(t) if **t == T::Mesh => "grid.mesh",
        T::Table => "info.table",
        T::Camera => "cam.camera",
        T::Material => "mat.material",
        T::List(t) if **t == T::Material => "mat.material",
        T::Light => "light.light",
        T::List(t) if **t == T::Light => "light.light",
        T::Image => "uvimg.image",
        T::Points => "fluid.points",
        T::String => "name.value",
        T::Int | T::Any => "one.value",
        T::Float => "onef.value",
        _ => return None,
    })
}
