//! Helpers every test module uses: where the project's files are, and running a graph.

use cgnodes::exec::{Executor, RunOptions, RunReport};
use cgnodes::node::{ExecContext, FileEnv};
use cgnodes::registry::Registry;
use cgnodes::types::Value;
use std::collections::BTreeMap;
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};

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
    let ins = inputs
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
    let mut ctx = ExecContext::standalone(decl, ins, &mut state, files, 0);
    (decl.exec.as_ref().unwrap())(&mut ctx).map_err(|e| e.to_string())?;
    let logs = ctx.logs().to_vec();
    Ok((ctx.take_outputs(), logs))
}
