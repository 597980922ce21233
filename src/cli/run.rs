//! `cgnodes run`: validates a graph and runs it over a frame range, with progress bars,
//! a run report per frame, and an optional profile (`--profile`, `--profile-json`).

use super::progress::{Monitor, Verbosity};
use super::validate::load_args;
use super::{RunArgs, EXIT_INVALID, EXIT_NODE_FAILED, EXIT_USAGE};
use crate::exec::{Executor, NodeStatus, RunOptions, RunReport};
use crate::graph::parse_frames;
use crate::node::FileEnv;
use crate::registry::Registry;
use std::path::PathBuf;

/// `cgnodes run GRAPH ...`: runs the graph once per frame; exit code 1 when a node failed.
/// With `--watch`, runs again after every change to the graph or its input files.
pub(super) fn cmd(registry: &Registry, args: RunArgs) -> i32 {
    let exec = match Executor::new(args.threads, args.cache.as_deref()) {
        Ok(e) => e,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_USAGE;
        }
    };
    let (code, inputs) = run_once(registry, &args, &exec);
    if !args.watch {
        return code;
    }
    watch_loop(registry, &args, &exec, inputs)
}

/// `--watch`: waits for a change to the graph file or the files the last valid graph read,
/// then runs again with the same executor, so only what changed (and what it feeds)
/// recomputes. Ends only when interrupted.
fn watch_loop(registry: &Registry, args: &RunArgs, exec: &Executor, inputs: Vec<PathBuf>) -> i32 {
    let (tx, rx) = std::sync::mpsc::channel();
    let mut w = match super::watch::FileWatch::new(move |p| {
        let _ = tx.send(p);
    }) {
        Ok(w) => w,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_USAGE;
        }
    };
    let mut watched = watch_list(args, inputs);
    w.set(&watched);
    loop {
        eprintln!(
            "watching {} file{} (Ctrl-C stops)",
            watched.len(),
            if watched.len() == 1 { "" } else { "s" }
        );
        let changed = super::watch::wait_quiet(&rx);
        if changed.is_empty() {
            return 0;
        }
        let names: Vec<String> = changed.iter().map(|p| p.display().to_string()).collect();
        eprintln!("changed: {}", names.join(", "));
        // A frame range starts again from its first frame: simulations restart.
        exec.reset_states();
        let (_, inputs) = run_once(registry, args, exec);
        // An invalid graph keeps the last valid graph's inputs watched.
        if !inputs.is_empty() {
            watched = watch_list(args, inputs);
            w.set(&watched);
        }
    }
}

/// The graph file, the `--f3d-aliases` file and the graph's input files.
fn watch_list(args: &RunArgs, inputs: Vec<PathBuf>) -> Vec<PathBuf> {
    let mut v = vec![args.load.graph.clone()];
    v.extend(args.load.f3d_aliases.clone());
    v.extend(inputs);
    v
}

/// One run of `run`: loads and validates the graph, runs its frames, writes the report; the
/// exit code and the files the graph reads (empty when it did not load).
fn run_once(registry: &Registry, args: &RunArgs, exec: &Executor) -> (i32, Vec<PathBuf>) {
    let (code, graph) = run_graph(registry, args, exec);
    let inputs = graph.map_or_else(Vec::new, |g| {
        crate::exec::input_files(&g, &file_env(args, &g.dir))
    });
    (code, inputs)
}

/// Where a run of the graph in `graph_dir` reads and writes, from `run`'s options.
fn file_env(args: &RunArgs, graph_dir: &std::path::Path) -> FileEnv {
    FileEnv {
        graph_dir: graph_dir.to_path_buf(),
        asset_dirs: args.load.assets.clone(),
        out_dir: args.out.clone(),
        allow_write_anywhere: args.allow_write_anywhere,
    }
}

/// Loads, validates and runs; the exit code and the graph when it loaded.
fn run_graph(
    registry: &Registry,
    args: &RunArgs,
    exec: &Executor,
) -> (i32, Option<crate::validate::ValidGraph>) {
    let targets = (!args.target.is_empty()).then_some(args.target.as_slice());
    let (graph, hint) = match load_args(registry, &args.load, targets) {
        Ok(g) => g,
        Err(c) => return (c, None),
    };
    for t in &args.target {
        if !graph.index.contains_key(t) {
            eprintln!(
                "error: --target '{t}' is not a node of {}",
                args.load.graph.display()
            );
            return (EXIT_USAGE, Some(graph));
        }
    }
    if targets.is_none() && graph.targets.is_empty() {
        eprintln!(
            "error: {}: nothing to run: no node writes a file; name a --target",
            args.load.graph.display()
        );
        return (EXIT_INVALID, Some(graph));
    }
    let (f0, f1) = match args.frames.as_deref().map(parse_frames).transpose() {
        Ok(r) => r.or(hint).unwrap_or((0, 0)),
        Err(e) => {
            eprintln!("error: {e}");
            return (EXIT_USAGE, Some(graph));
        }
    };
    let (f0, f1) = match shard_frames(&graph, args, (f0, f1)) {
        Ok(Some(r)) => r,
        Ok(None) => return (0, Some(graph)),
        Err(c) => return (c, Some(graph)),
    };
    let monitor = Monitor::new(Verbosity::from_flags(args.quiet, args.verbose));
    let opts = RunOptions {
        targets: (!args.target.is_empty()).then(|| args.target.clone()),
        files: file_env(args, &graph.dir),
        progress: monitor.progress_fn(),
        log: monitor.log_fn(),
        measure_memory: args.profile || args.profile_json.is_some(),
        recompute: Vec::new(),
        // The command line reads no outputs after the run: writers are the targets.
        read_outputs: Vec::new(),
        all_outputs: false,
        max_memory: args.max_memory,
    };
    let mut code = 0;
    let mut profile = Vec::new();
    monitor.start_frames(f0, f1);
    let mut collected = crate::report::Collector::default();
    if !args.no_report && args.shard.shard.is_none() {
        collected.prefetch_previews(registry.mesh_hooks);
    }
    for frame in f0..=f1 {
        if f1 > f0 {
            monitor.set_prefix(format!("[frame {frame}] "));
        }
        let report = exec.run(&graph, &opts, frame);
        monitor.suspend(|| {
            if !args.quiet {
                print_report(&report, f1 > f0, monitor.level());
            }
            for e in report.errors() {
                eprintln!("error: {e}");
            }
            if frame < f1 {
                print_stops(exec, &report, f1);
            }
            if args.profile {
                print_profile(&report);
            }
        });
        monitor.frame_done(f0, f1, frame);
        if !report.ok() {
            code = EXIT_NODE_FAILED;
        }
        profile.push(profile_json(&report));
        collected.add(&report);
    }
    let code = code.max(finish(registry, args, exec, &graph, &collected, &profile));
    (code, Some(graph))
}

/// After the frames: the run report (not for a shard: it would cover only its frames, and
/// shards share one output folder), the disk cache trimmed to `--cache-size`, and
/// `--profile-json`. Returns `EXIT_NODE_FAILED` when the profile could not be written, else 0.
fn finish(
    registry: &Registry,
    args: &RunArgs,
    exec: &Executor,
    graph: &crate::validate::ValidGraph,
    collected: &crate::report::Collector,
    profile: &[serde_json::Value],
) -> i32 {
    if !args.no_report && args.shard.shard.is_none() {
        match crate::report::write_run_report(graph, collected, &args.out, registry.mesh_hooks) {
            Ok(p) if !args.quiet => eprintln!("report: {}", p.display()),
            Ok(_) => {}
            Err(e) => eprintln!("warning: report not written: {e}"),
        }
    }
    if let Some(ev) = exec.evict_disk_cache(args.cache_size) {
        if ev.removed > 0 && !args.quiet {
            eprintln!(
                "cache: removed {} least recently used entries ({:.1} MiB) to stay under --cache-size; {:.1} MiB kept",
                ev.removed,
                ev.freed as f64 / 1048576.0,
                ev.kept as f64 / 1048576.0
            );
        }
    }
    if let Some(p) = &args.profile_json {
        let text = serde_json::to_string_pretty(profile).unwrap_or_default();
        if let Err(e) = crate::io::write_atomic(p, |w| w.write_all(text.as_bytes())) {
            eprintln!("error: {}: {e}", p.display());
            return EXIT_NODE_FAILED;
        }
    }
    0
}

/// This process's frames under `--shard I/N` (a contiguous block of `f0..=f1`), `None` when
/// the shard has no frames (more shards than frames), or the exit code of a refusal: a graph
/// with a node that keeps state between frames cannot be split by frames.
fn shard_frames(
    graph: &crate::validate::ValidGraph,
    args: &RunArgs,
    (f0, f1): (i64, i64),
) -> Result<Option<(i64, i64)>, i32> {
    let shard = match args.shard.resolve() {
        Ok(Some(s)) => s,
        Ok(None) => return Ok(Some((f0, f1))),
        Err(e) => {
            eprintln!("error: {e}");
            return Err(EXIT_USAGE);
        }
    };
    if shard.count > 1 {
        if let Some(n) = graph.nodes.iter().find(|n| n.decl.stateful) {
            eprintln!(
                "error: --shard {shard}: {}: node '{}' ({}) keeps state between frames, so each frame needs the ones before it and the frames cannot be split between processes. Run the whole range in one process, or shard a sweep over this graph instead (cgnodes sweep ... --shard I/N), which splits whole runs",
                graph.file.display(),
                n.id,
                n.decl.type_name
            );
            return Err(EXIT_USAGE);
        }
    }
    let r = shard.frames(f0, f1);
    if r.is_none() && !args.quiet {
        eprintln!("shard {shard}: no frames of {f0}..{f1} (more shards than frames)");
    }
    Ok(r)
}

/// Parses `--cache-size`: a size as `node::parse_size` reads it (`500MiB`, `2G`), or `0` for
/// no limit.
pub(super) fn parse_cache_size(s: &str) -> Result<u64, String> {
    if s.trim() == "0" {
        Ok(0)
    } else {
        crate::node::parse_size(s)
    }
}

/// Says once, at the frame where it happens, that a simulation which failed (or could not
/// run) stays stopped with everything downstream for the rest of the range.
fn print_stops(exec: &Executor, r: &RunReport, last: i64) {
    for n in &r.nodes {
        if matches!(n.status, NodeStatus::Failed(_) | NodeStatus::Blocked { .. })
            && exec.stopped_since(&n.id) == Some(r.frame)
        {
            eprintln!(
                "error: {}: node '{}' ({}) keeps state between frames: it and the nodes it feeds stay failed for frames {}..{last}",
                r.file.display(),
                n.id,
                n.node_type,
                r.frame + 1
            );
        }
    }
}

/// Prints what a frame did. The log lines of nodes that ran were printed live (`Monitor`);
/// those of cached nodes are replayed here.
fn print_report(r: &RunReport, frames: bool, level: Verbosity) {
    let prefix = if frames {
        format!("[frame {}] ", r.frame)
    } else {
        String::new()
    };
    for n in &r.nodes {
        if level == Verbosity::Verbose {
            let what = match &n.status {
                NodeStatus::Ran => format!("ran in {:.2} ms", n.ms),
                NodeStatus::Cached => "cached".to_string(),
                NodeStatus::Skipped => "skipped (no requested output needs it)".to_string(),
                NodeStatus::Failed(_) => format!("failed after {:.2} ms", n.ms),
                NodeStatus::Blocked { by } => format!("blocked by '{by}'"),
                NodeStatus::Stopped { since } => format!("stopped since frame {since}"),
            };
            eprintln!("{prefix}{} ({}): {what}", n.id, n.node_type);
        }
        if matches!(n.status, NodeStatus::Cached) {
            for l in &n.logs {
                eprintln!("{prefix}{}: {l}", n.id);
            }
        }
        for w in &n.written {
            if matches!(n.status, NodeStatus::Ran) {
                eprintln!("{prefix}wrote {}", w.display());
            }
        }
    }
    let count = |f: fn(&NodeStatus) -> bool| r.nodes.iter().filter(|n| f(&n.status)).count();
    let skipped: Vec<&str> = r
        .nodes
        .iter()
        .filter(|n| matches!(n.status, NodeStatus::Skipped))
        .map(|n| n.id.as_str())
        .collect();
    eprintln!(
        "{prefix}ran {}, cached {}, failed {}, blocked {}{}, skipped {}{} in {:.1} ms",
        count(|s| matches!(s, NodeStatus::Ran)),
        count(|s| matches!(s, NodeStatus::Cached)),
        count(|s| matches!(s, NodeStatus::Failed(_))),
        count(|s| matches!(s, NodeStatus::Blocked { .. })),
        match count(|s| matches!(s, NodeStatus::Stopped { .. })) {
            0 => String::new(),
            k => format!(", stopped {k}"),
        },
        skipped.len(),
        if skipped.is_empty() || skipped.len() > 10 {
            String::new()
        } else {
            format!(" ({})", skipped.join(", "))
        },
        r.total_ms
    );
}

fn print_profile(r: &RunReport) {
    eprintln!(
        "{:<20} {:<20} {:>10} {:>8} {:>10}",
        "node", "type", "ms", "status", "rss MiB"
    );
    for n in &r.nodes {
        let st = match &n.status {
            NodeStatus::Ran => "ran",
            NodeStatus::Cached => "cached",
            NodeStatus::Skipped => continue,
            NodeStatus::Failed(_) => "failed",
            NodeStatus::Blocked { .. } => "blocked",
            NodeStatus::Stopped { .. } => "stopped",
        };
        eprintln!(
            "{:<20} {:<20} {:>10.2} {:>8} {:>10.1}",
            n.id,
            n.node_type,
            n.ms,
            st,
            n.rss_kib as f64 / 1024.0
        );
    }
    eprintln!(
        "total {:.2} ms, peak memory {:.1} MiB",
        r.total_ms,
        r.peak_rss_kib as f64 / 1024.0
    );
}

/// The profile of a run as JSON: per-node wall time, status and memory.
pub fn profile_json(r: &RunReport) -> serde_json::Value {
    let nodes: Vec<_> = r
        .nodes
        .iter()
        .map(|n| {
            let st = match &n.status {
                NodeStatus::Ran => "ran",
                NodeStatus::Cached => "cached",
                NodeStatus::Skipped => "skipped",
                NodeStatus::Failed(_) => "failed",
                NodeStatus::Blocked { .. } => "blocked",
                NodeStatus::Stopped { .. } => "stopped",
            };
            serde_json::json!({"id": n.id, "type": n.node_type, "status": st, "ms": n.ms, "rss_kib": n.rss_kib})
        })
        .collect();
    serde_json::json!({"frame": r.frame, "total_ms": r.total_ms, "peak_rss_kib": r.peak_rss_kib, "nodes": nodes})
}

#[cfg(test)]
mod tests {
    use super::parse_cache_size;

    #[test]
    fn cache_sizes_parse_and_zero_means_no_limit() {
        assert_eq!(parse_cache_size("0"), Ok(0));
        assert_eq!(parse_cache_size("1024"), Ok(1024));
        assert_eq!(parse_cache_size("1GiB"), Ok(1 << 30));
        assert_eq!(parse_cache_size("500 MiB"), Ok(500 << 20));
        assert_eq!(parse_cache_size("2G"), Ok(2_000_000_000));
        assert!(parse_cache_size("lots").is_err());
        assert!(parse_cache_size("3 parsecs").is_err());
        assert!(parse_cache_size("99999999999TiB").is_err());
    }
}
