//! The `cgnodes` command line. `main_with(registry)` lets a crate that adds its own nodes build
//! a complete `cgnodes` binary in a few lines.
//!
//! Exit codes: 0 success; 1 some node failed (the others still ran); 2 bad command line;
//! 3 the graph could not be loaded or did not validate.

use crate::exec::{Executor, NodeStatus, RunOptions, RunReport};
use crate::graph::{self, Graph};
use crate::node::FileEnv;
use crate::registry::Registry;
use crate::validate::{validate_with, GraphError, ValidGraph};
use clap::{Parser, Subcommand};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Exit code: a node failed.
pub const EXIT_NODE_FAILED: i32 = 1;
/// Exit code: bad command line.
pub const EXIT_USAGE: i32 = 2;
/// Exit code: the graph could not be loaded or is invalid.
pub const EXIT_INVALID: i32 = 3;

#[derive(Parser)]
#[command(
    name = "cgnodes",
    version,
    about = "Run computer-graphics node graphs from JSON files."
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
    /// A plugin folder, or a folder of plugin folders, whose nodes are added (repeatable;
    /// also searched: CGNODES_PLUGIN_PATH and ~/.config/cgnodes/plugins).
    #[arg(long = "plugins", value_name = "DIR", global = true)]
    plugins: Vec<PathBuf>,
}

#[derive(Subcommand)]
enum Cmd {
    /// Validate and run a graph.
    Run(RunArgs),
    /// Check a graph without running it.
    Validate {
        /// Graph file.
        graph: PathBuf,
        /// Set an input literal: NODE.SOCKET=VALUE (repeatable).
        #[arg(long = "set", value_name = "NODE.SOCKET=VALUE")]
        set: Vec<String>,
    },
    /// List every node type with its sockets.
    Nodes {
        /// Print the declarations as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Show one node type.
    Describe {
        /// Node type.
        node_type: String,
    },
    /// Print the JSON Schema of the graph format.
    Schema,
    /// Print a graph as Graphviz dot.
    Dot {
        /// Graph file.
        graph: PathBuf,
    },
    /// Run a graph for every combination of parameter values; write a CSV and a chart.
    Sweep(SweepArgs),
    /// Chart columns of one or more CSV files (for example a sweep beside a peer's results).
    Chart(ChartArgs),
    /// Convert a Framework3D saved node tree to a cgnodes graph.
    ImportF3d {
        /// Framework3D JSON file.
        input: PathBuf,
        /// Output graph file.
        #[arg(short = 'o', long = "output")]
        output: PathBuf,
        /// JSON file mapping custom Framework3D node names onto cgnodes nodes.
        #[arg(long = "f3d-aliases")]
        aliases: Option<PathBuf>,
    },
}

#[derive(clap::Args)]
struct ChartArgs {
    /// CSV files with a header row.
    #[arg(required = true)]
    csv: Vec<PathBuf>,
    /// Column for the x axis.
    #[arg(long)]
    x: String,
    /// Column for the y axis.
    #[arg(long)]
    y: String,
    /// Column whose values name the series (default: one series per file, named after it).
    #[arg(long)]
    series: Option<String>,
    /// Chart to write (.svg or .png).
    #[arg(long)]
    plot: PathBuf,
    /// Chart title.
    #[arg(long, default_value = "")]
    title: String,
    /// Logarithmic x axis.
    #[arg(long)]
    log_x: bool,
    /// Logarithmic y axis.
    #[arg(long)]
    log_y: bool,
}

#[derive(clap::Args)]
struct SweepArgs {
    /// A graph file, or a sweep file (JSON with a "graph" field; see docs/sweep.md).
    target: PathBuf,
    /// Values to try: NODE.PARAM=v1,v2,... (repeatable; every combination runs).
    #[arg(long = "vary", value_name = "NODE.PARAM=V1,V2,...")]
    vary: Vec<String>,
    /// Fixed override for every run: NODE.SOCKET=VALUE (repeatable).
    #[arg(long = "set", value_name = "NODE.SOCKET=VALUE")]
    set: Vec<String>,
    /// Runs per combination.
    #[arg(long)]
    repeat: Option<usize>,
    /// Output to record: NODE.SOCKET, or NODE.SOCKET:COLUMN[:last|mean|max|min|sum] for a table.
    #[arg(long = "measure", value_name = "NODE.SOCKET[:COLUMN[:SUMMARY]]")]
    measure: Vec<String>,
    /// CSV file to write.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Chart to write (.svg or .png).
    #[arg(long)]
    plot: Option<PathBuf>,
    /// X axis: time, time:NODE, a measure or a varied parameter.
    #[arg(long)]
    x: Option<String>,
    /// Y axis: a measure (default: the first).
    #[arg(long)]
    y: Option<String>,
    /// Varied parameter whose values name the series.
    #[arg(long)]
    series: Option<String>,
    /// Logarithmic x axis.
    #[arg(long)]
    log_x: bool,
    /// Logarithmic y axis.
    #[arg(long)]
    log_y: bool,
    /// Chart title.
    #[arg(long)]
    title: Option<String>,
    /// Frame range A..B per run.
    #[arg(long)]
    frames: Option<String>,
    /// Output directory for the graph's writers (default: a temporary folder).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Worker threads.
    #[arg(long)]
    threads: Option<usize>,
}

#[derive(clap::Args)]
struct RunArgs {
    /// Graph file (cgnodes JSON or a Framework3D saved node tree).
    graph: PathBuf,
    /// Output directory; writer nodes write under it.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Set an input literal: NODE.SOCKET=VALUE (repeatable).
    #[arg(long = "set", value_name = "NODE.SOCKET=VALUE")]
    set: Vec<String>,
    /// Evaluate these nodes instead of the graph's outputs (repeatable).
    #[arg(long = "target", value_name = "NODE")]
    target: Vec<String>,
    /// Frame range A..B (inclusive); the graph runs once per frame.
    #[arg(long)]
    frames: Option<String>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Content-addressed result cache folder.
    #[arg(long)]
    cache: Option<PathBuf>,
    /// Further folders searched for input files.
    #[arg(long = "assets")]
    assets: Vec<PathBuf>,
    /// Let writers use absolute paths and '..'.
    #[arg(long)]
    allow_write_anywhere: bool,
    /// Print per-node wall time, cache hits and memory.
    #[arg(long)]
    profile: bool,
    /// Write the profile as JSON.
    #[arg(long = "profile-json")]
    profile_json: Option<PathBuf>,
    /// Print only errors.
    #[arg(long, short)]
    quiet: bool,
    /// JSON file mapping custom Framework3D node names onto cgnodes nodes.
    #[arg(long = "f3d-aliases")]
    f3d_aliases: Option<PathBuf>,
}

/// Runs the command line with `registry` (`Registry::builtin()` plus anything a crate adds).
/// Returns the process exit code.
pub fn main_with(registry: Registry) -> i32 {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() { EXIT_USAGE } else { 0 };
        }
    };
    let registry = match crate::plugin::cli_registry(registry, &cli.plugins) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_USAGE;
        }
    };
    match cli.cmd {
        Cmd::Run(args) => cmd_run(&registry, args),
        Cmd::Validate { graph, set } => match load_valid(&registry, &graph, &set) {
            Ok(g) => {
                println!("{}: ok ({} nodes)", graph.display(), g.nodes.len());
                0
            }
            Err(code) => code,
        },
        Cmd::Nodes { json } => {
            if json {
                let all: Vec<_> = registry.iter().map(|d| d.as_ref().clone()).collect();
                println!("{}", serde_json::to_string_pretty(&all).unwrap_or_default());
            } else {
                for d in registry.iter() {
                    let src = if d.source == "builtin" {
                        String::new()
                    } else {
                        format!("  [{}]", d.source)
                    };
                    println!("{:<24} {}{src}", d.type_name, d.doc);
                    println!("{:<24}   in:  {}", "", sockets(&d.inputs));
                    println!("{:<24}   out: {}", "", sockets(&d.outputs));
                }
            }
            0
        }
        Cmd::Describe { node_type } => match registry.get(&node_type) {
            Some(d) => {
                print!("{}", describe(d));
                0
            }
            None => {
                let hint = registry
                    .closest(&node_type)
                    .map(|s| format!(" (did you mean '{s}'?)"))
                    .unwrap_or_default();
                eprintln!("error: unknown node type '{node_type}'{hint}");
                EXIT_USAGE
            }
        },
        Cmd::Schema => {
            println!(
                "{}",
                serde_json::to_string_pretty(&graph::schema()).unwrap_or_default()
            );
            0
        }
        Cmd::Dot { graph } => match load_valid(&registry, &graph, &[]) {
            Ok(g) => {
                print!("{}", g.to_dot());
                0
            }
            Err(c) => c,
        },
        Cmd::Sweep(args) => cmd_sweep(&registry, args),
        Cmd::Chart(args) => match chart_from_csv(&args) {
            Ok(()) => 0,
            Err(e) => {
                eprintln!("error: {e}");
                EXIT_INVALID
            }
        },
        Cmd::ImportF3d {
            input,
            output,
            aliases,
        } => cmd_import(&input, &output, aliases.as_deref()),
    }
}

/// Splits one CSV line, honouring double quotes.
fn csv_split(line: &str) -> Vec<String> {
    let mut out = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                chars.next();
                if let Some(s) = out.last_mut() {
                    s.push('"');
                }
            }
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(String::new()),
            c => {
                if let Some(s) = out.last_mut() {
                    s.push(c)
                }
            }
        }
    }
    out
}

fn chart_from_csv(a: &ChartArgs) -> Result<(), String> {
    use crate::chart::{Chart, Series};
    let mut chart = Chart {
        title: a.title.clone(),
        x_label: a.x.clone(),
        y_label: a.y.clone(),
        log_x: a.log_x,
        log_y: a.log_y,
        ..Default::default()
    };
    for f in &a.csv {
        let text = std::fs::read_to_string(f).map_err(|e| format!("{}: {e}", f.display()))?;
        let mut lines = text.lines().filter(|l| !l.trim().is_empty());
        let head = csv_split(
            lines
                .next()
                .ok_or_else(|| format!("{}: empty", f.display()))?,
        );
        let col = |name: &str| {
            head.iter()
                .position(|h| h == name)
                .ok_or_else(|| format!("{}: no column '{name}'", f.display()))
        };
        let (ix, iy) = (col(&a.x)?, col(&a.y)?);
        let is = a.series.as_deref().map(col).transpose()?;
        let status = head.iter().position(|h| h == "status");
        let file_label = f
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_default();
        for line in lines {
            let row = csv_split(line);
            let num = |i: usize| row.get(i).and_then(|s| s.trim().parse::<f64>().ok());
            let Some(x) = num(ix) else { continue };
            if status
                .and_then(|i| row.get(i))
                .is_some_and(|s| s == "failed")
            {
                chart.failures.push((x, file_label.clone()));
                continue;
            }
            let Some(y) = num(iy) else { continue };
            let label = match is {
                Some(i) => row.get(i).cloned().unwrap_or_default(),
                None => file_label.clone(),
            };
            match chart.series.iter_mut().find(|s| s.label == label) {
                Some(s) => s.points.push((x, y)),
                None => chart.series.push(Series {
                    label,
                    points: vec![(x, y)],
                }),
            }
        }
    }
    for s in &mut chart.series {
        s.points.sort_by(|p, q| p.0.total_cmp(&q.0));
    }
    crate::chart::draw(&chart, &a.plot)
}

fn cmd_sweep(registry: &Registry, a: SweepArgs) -> i32 {
    use crate::sweep::{parse_vary, SweepSpec};
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
    spec.csv = a.csv.map(here).or(spec.csv);
    spec.plot = a.plot.map(here).or(spec.plot);
    spec.out = a.out.map(here).or(spec.out);
    spec.x = a.x.or(spec.x);
    spec.y = a.y.or(spec.y);
    spec.series = a.series.or(spec.series);
    spec.title = a.title.or(spec.title);
    spec.frames = a.frames.or(spec.frames);
    spec.log_x |= a.log_x;
    spec.log_y |= a.log_y;
    match crate::sweep::run_and_write(&spec, &base, registry, a.threads) {
        Ok(rows) => {
            let failed = rows.iter().filter(|r| !r.ok).count();
            eprintln!("{} runs, {} failed", rows.len(), failed);
            if spec.csv.is_none() {
                print!("{}", crate::sweep::to_csv(&spec, &rows));
            }
            0
        }
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_INVALID
        }
    }
}

fn cmd_import(input: &Path, output: &Path, aliases: Option<&Path>) -> i32 {
    let read_json = |p: &Path| -> Result<serde_json::Value, String> {
        let t = std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()))?;
        serde_json::from_str(&t).map_err(|e| format!("{}: {e}", p.display()))
    };
    let result = (|| -> Result<(), String> {
        let raw = read_json(input)?;
        let al = match aliases {
            Some(a) => serde_json::from_value(read_json(a)?)
                .map_err(|e| format!("{}: {e}", a.display()))?,
            None => crate::f3d::Aliases::default(),
        };
        let (g, missing) = crate::f3d::import_lenient(&raw, &al, &Registry::builtin())
            .map_err(|e| format!("{}: {e}", input.display()))?;
        if !missing.is_empty() {
            eprintln!(
                "warning: {}: the graph was converted, but it will not run until these exist: {}",
                input.display(),
                missing.join(", ")
            );
        }
        let text = serde_json::to_string_pretty(&g).map_err(|e| e.to_string())?;
        crate::io::write_atomic(output, |w| w.write_all(text.as_bytes()))
            .map_err(|e| format!("{}: {e}", output.display()))
    })();
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_INVALID
        }
    }
}

fn sockets(s: &[crate::node::SocketDecl]) -> String {
    s.iter()
        .map(|s| format!("{}: {}", s.name, s.ty))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A human description of a node type: doc, then sockets with defaults, ranges and choices.
pub fn describe(d: &crate::node::NodeDecl) -> String {
    let mut s = format!("{} — {}\n", d.type_name, d.doc);
    if d.source != "builtin" {
        s.push_str(&format!("from: {}\n", d.source));
    }
    let mut flags = Vec::new();
    if d.stateful {
        flags.push("stateful (keeps state between frames)");
    } else if d.time_dependent {
        flags.push("depends on the frame");
    }
    if d.sink {
        flags.push("sink (evaluated by default)");
    }
    if !flags.is_empty() {
        s.push_str(&format!("{}\n", flags.join(", ")));
    }
    for (title, list) in [("inputs", &d.inputs), ("outputs", &d.outputs)] {
        s.push_str(&format!("{title}:\n"));
        for x in list.iter() {
            let mut extra = Vec::new();
            if let Some(v) = &x.default {
                extra.push(format!("default {v}"));
            }
            match (x.min, x.max) {
                (Some(a), Some(b)) => extra.push(format!("range {a}..{b}")),
                (Some(a), None) => extra.push(format!(">= {a}")),
                (None, Some(b)) => extra.push(format!("<= {b}")),
                _ => {}
            }
            if let Some(c) = &x.choices {
                extra.push(format!("one of {}", c.join(" | ")));
            }
            if x.optional {
                extra.push("optional".into());
            }
            let extra = if extra.is_empty() {
                String::new()
            } else {
                format!(" [{}]", extra.join("; "))
            };
            s.push_str(&format!(
                "  {:<16} {:<12} {}{extra}\n",
                x.name,
                x.ty.to_string(),
                x.doc
            ));
        }
    }
    s
}

/// Applies `--set NODE.SOCKET=VALUE` overrides to a graph's literals. The value is read as
/// JSON when it parses, else as a string, and checked later by validation against the
/// socket's type.
pub fn apply_sets(g: &mut Graph, sets: &[String]) -> Result<(), String> {
    for s in sets {
        let (lhs, val) = s
            .split_once('=')
            .ok_or_else(|| format!("--set '{s}': expected NODE.SOCKET=VALUE"))?;
        let (node, socket) = graph::split_link(lhs)
            .ok_or_else(|| format!("--set '{s}': expected NODE.SOCKET=VALUE"))?;
        if !g.spec.nodes.contains_key(node) {
            let hint = crate::registry::closest(node, g.spec.nodes.keys().map(String::as_str))
                .map(|h| format!(" (did you mean '{h}'?)"))
                .unwrap_or_default();
            return Err(format!("--set '{s}': no node '{node}' in the graph{hint}"));
        }
        let Some(spec) = g.spec.nodes.get_mut(node) else {
            continue;
        };
        if spec.inputs.contains_key(socket) {
            return Err(format!("--set '{s}': input '{socket}' of node '{node}' is linked; a literal cannot replace a link"));
        }
        let j = serde_json::from_str(val)
            .unwrap_or_else(|_| serde_json::Value::String(val.to_string()));
        spec.params.insert(socket.to_string(), j);
    }
    Ok(())
}

/// Loads, applies overrides and validates, printing errors; `Err` is the exit code.
pub fn load_valid(registry: &Registry, path: &Path, sets: &[String]) -> Result<ValidGraph, i32> {
    load_valid_with(registry, path, sets, &crate::f3d::Aliases::default(), &[])
}

/// Reads Framework3D aliases (`--f3d-aliases FILE`).
pub fn read_aliases(p: &Path) -> Result<crate::f3d::Aliases, String> {
    let t = std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()))?;
    serde_json::from_str(&t).map_err(|e| format!("{}: {e}", p.display()))
}

/// Like `load_valid`, with aliases for custom Framework3D node names.
pub fn load_valid_with(
    registry: &Registry,
    path: &Path,
    sets: &[String],
    aliases: &crate::f3d::Aliases,
    assets: &[PathBuf],
) -> Result<ValidGraph, i32> {
    let mut g = match graph::load_with(path, aliases) {
        Ok(g) => g,
        Err(e) => {
            eprintln!("error: {e}");
            return Err(EXIT_INVALID);
        }
    };
    if let Err(e) = apply_sets(&mut g, sets) {
        eprintln!("error: {e}");
        return Err(EXIT_USAGE);
    }
    validate_with(&g, registry, assets).map_err(|errs| {
        print_graph_errors(&errs);
        EXIT_INVALID
    })
}

fn print_graph_errors(errs: &[GraphError]) {
    for e in errs {
        eprintln!("error: {e}");
    }
    eprintln!(
        "{} error{} found; nothing was run",
        errs.len(),
        if errs.len() == 1 { "" } else { "s" }
    );
}

/// Parses `A..B` (inclusive) or a single frame `A`.
pub fn parse_frames(s: &str) -> Result<(i64, i64), String> {
    let (a, b) = match s.split_once("..") {
        Some((a, b)) => (a, b.trim_start_matches('=')),
        None => (s, s),
    };
    let a: i64 = a
        .trim()
        .parse()
        .map_err(|_| format!("--frames '{s}': expected A..B"))?;
    let b: i64 = b
        .trim()
        .parse()
        .map_err(|_| format!("--frames '{s}': expected A..B"))?;
    if b < a {
        return Err(format!(
            "--frames '{s}': the last frame comes before the first"
        ));
    }
    Ok((a, b))
}

fn cmd_run(registry: &Registry, args: RunArgs) -> i32 {
    let aliases = match args.f3d_aliases.as_deref().map(read_aliases).transpose() {
        Ok(a) => a.unwrap_or_default(),
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_USAGE;
        }
    };
    let graph = match load_valid_with(registry, &args.graph, &args.set, &aliases, &args.assets) {
        Ok(g) => g,
        Err(c) => return c,
    };
    for t in &args.target {
        if !graph.index.contains_key(t) {
            eprintln!(
                "error: --target '{t}' is not a node of {}",
                args.graph.display()
            );
            return EXIT_USAGE;
        }
    }
    let hint = graph::load_with(&args.graph, &aliases)
        .ok()
        .and_then(|g| g.spec.frames_hint());
    let (f0, f1) = match args.frames.as_deref().map(parse_frames).transpose() {
        Ok(r) => r.or(hint).unwrap_or((0, 0)),
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_USAGE;
        }
    };
    let exec = match Executor::new(args.threads, args.cache.as_deref()) {
        Ok(e) => e,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_USAGE;
        }
    };
    let show_progress =
        !args.quiet && std::io::stderr().is_terminal() && std::env::var_os("CI").is_none();
    let bars = show_progress.then(indicatif::MultiProgress::new);
    let progress: Option<crate::node::ProgressFn> = bars.as_ref().map(|mp| {
        let mp = mp.clone();
        let map: Arc<std::sync::Mutex<std::collections::HashMap<String, indicatif::ProgressBar>>> =
            Arc::default();
        Arc::new(move |node: &str, f: f64| {
            let mut m = map.lock().unwrap_or_else(|p| p.into_inner());
            let bar = m.entry(node.to_string()).or_insert_with(|| {
                let b = mp.add(indicatif::ProgressBar::new(1000));
                if let Ok(st) = indicatif::ProgressStyle::with_template(
                    "{prefix:>16} {bar:30} {percent:>3}% {elapsed}",
                ) {
                    b.set_style(st);
                }
                b.set_prefix(node.to_string());
                b
            });
            bar.set_position((f * 1000.0) as u64);
            if f >= 1.0 {
                bar.finish_and_clear();
            }
        }) as crate::node::ProgressFn
    });
    let opts = RunOptions {
        targets: (!args.target.is_empty()).then(|| args.target.clone()),
        files: FileEnv {
            graph_dir: graph.dir.clone(),
            asset_dirs: args.assets.clone(),
            out_dir: args.out.clone(),
            allow_write_anywhere: args.allow_write_anywhere,
        },
        progress,
        measure_memory: args.profile || args.profile_json.is_some(),
        recompute: Vec::new(),
        // The command line reads no outputs after the run: writers are the targets.
        read_outputs: Vec::new(),
        all_outputs: false,
    };
    let mut code = 0;
    let mut profile = Vec::new();
    for frame in f0..=f1 {
        let report = exec.run(&graph, &opts, frame);
        if !args.quiet {
            print_report(&report, f1 > f0);
        }
        for e in report.errors() {
            eprintln!("error: {e}");
        }
        if args.profile {
            print_profile(&report);
        }
        if !report.ok() {
            code = EXIT_NODE_FAILED;
        }
        profile.push(profile_json(&report));
    }
    if let Some(p) = &args.profile_json {
        let text = serde_json::to_string_pretty(&profile).unwrap_or_default();
        if let Err(e) = crate::io::write_atomic(p, |w| w.write_all(text.as_bytes())) {
            eprintln!("error: {}: {e}", p.display());
            code = code.max(EXIT_NODE_FAILED);
        }
    }
    code
}

fn print_report(r: &RunReport, frames: bool) {
    let prefix = if frames {
        format!("[frame {}] ", r.frame)
    } else {
        String::new()
    };
    for n in &r.nodes {
        for l in &n.logs {
            eprintln!("{prefix}{}: {l}", n.id);
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
        "{prefix}ran {}, cached {}, failed {}, blocked {}, skipped {}{} in {:.1} ms",
        count(|s| matches!(s, NodeStatus::Ran)),
        count(|s| matches!(s, NodeStatus::Cached)),
        count(|s| matches!(s, NodeStatus::Failed(_))),
        count(|s| matches!(s, NodeStatus::Blocked { .. })),
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
            };
            serde_json::json!({"id": n.id, "type": n.node_type, "status": st, "ms": n.ms, "rss_kib": n.rss_kib})
        })
        .collect();
    serde_json::json!({"frame": r.frame, "total_ms": r.total_ms, "peak_rss_kib": r.peak_rss_kib, "nodes": nodes})
}
