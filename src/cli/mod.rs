//! The `cgnodes` command line: the clap definitions and the dispatch to one module per
//! subcommand. `main_with(registry)` lets a crate that adds its own nodes build a complete
//! `cgnodes` binary in a few lines.
//!
//! Exit codes: 0 success; 1 some node failed (the others still ran); 2 bad command line;
//! 3 the graph could not be loaded or did not validate; 130 interrupted (SIGINT, SIGTERM).

mod chart;
mod describe;
mod dot;
mod error;
#[cfg(feature = "render")]
mod f3d_project;
mod import_f3d;
mod nodes;
mod progress;
mod provenance;
mod run;
mod schema;
mod serve;
mod sweep;
mod sweep_merge;
mod validate;
mod watch;

use crate::registry::Registry;
use clap::{Parser, Subcommand};
use std::path::PathBuf;

pub use crate::graph::{apply_sets, parse_frames};
pub use describe::describe;
pub use error::FileError;
pub use run::profile_json;
pub use validate::{load_valid, load_valid_with, read_aliases};

/// Exit code: a node failed.
pub const EXIT_NODE_FAILED: i32 = 1;
/// Exit code: bad command line.
pub const EXIT_USAGE: i32 = 2;
/// Exit code: the graph could not be loaded or is invalid.
pub const EXIT_INVALID: i32 = 3;

/// Exit codes, shown at the end of `cgnodes --help`.
const EXIT_CODES: &str = "Exit codes:
  0    everything asked for ran (or was answered from the cache)
  1    a node failed; the rest of the graph ran and the report says what could not
  2    bad command line (unknown option, bad --set or --frames value, plugin folder error)
  3    the graph could not be loaded or is invalid (JSON, unknown node type, type mismatch,
       cycle, missing link), or sweep-merge found parts missing or repeated
  130  interrupted (Ctrl-C or SIGTERM): plugin processes killed, temporaries removed

Examples:
  cgnodes run graphs/tutte_cotangent_circle.json --out out
  cgnodes nodes
  cgnodes describe arap";

#[derive(Parser)]
#[command(
    name = "cgnodes",
    version,
    about = "Run computer-graphics node graphs from JSON files.",
    after_help = EXIT_CODES
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
    #[command(
        after_help = "Example: cgnodes run graphs/arap_camelhead.json --out out --set arap.iterations=20 --profile"
    )]
    Run(RunArgs),
    /// Serve a local web page for a graph: its outputs, and its parameters as widgets that
    /// rerun it (docs/serve.md).
    #[command(
        after_help = "Example: cgnodes serve graphs/tutte_cotangent_circle.json --out out --port 0"
    )]
    Serve(serve::ServeArgs),
    /// Check every node of a graph without running it (exit 3 on any error).
    #[command(after_help = "Example: cgnodes validate graphs/cloth_sphere.json")]
    Validate(ValidateArgs),
    /// List every node type with its sockets.
    #[command(after_help = "Example: cgnodes nodes --json > nodes.json")]
    Nodes {
        /// Print the declarations as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Show one node type.
    #[command(after_help = "Example: cgnodes describe mass_spring")]
    Describe {
        /// Node type.
        node_type: String,
    },
    /// Print the JSON Schema of the graph format, every node type's parameters typed (with
    /// `--plugins`, the plugins' too), for editors: name it in a graph's `"$schema"`.
    #[command(
        after_help = "Example: cgnodes schema > graph.schema.json, then \"$schema\": \"graph.schema.json\" in a graph"
    )]
    Schema {
        /// Only the file's structure, parameters untyped.
        #[arg(long)]
        untyped: bool,
    },
    /// Print a graph as Graphviz dot.
    #[command(
        after_help = "Example: cgnodes dot graphs/tutte_cotangent_circle.json | dot -Tsvg > graph.svg"
    )]
    Dot(GraphArgs),
    /// Run a graph for every combination of parameter values; write a CSV and a chart.
    #[command(
        after_help = "Example: cgnodes sweep bench/sweeps/image_svd_rank.json --csv svd.csv --plot svd.svg"
    )]
    Sweep(SweepArgs),
    /// Merge the CSV parts of a sharded sweep (`sweep --shard I/N`) into the CSV and chart of
    /// the whole sweep, checking that every combination is present exactly once.
    #[command(
        after_help = "Example: cgnodes sweep-merge part-*.csv --csv all.csv --plot all.svg (see docs/cluster.md)"
    )]
    SweepMerge(SweepMergeArgs),
    /// Chart columns of one or more CSV files (for example a sweep beside a peer's results).
    #[command(
        after_help = "Example: cgnodes chart svd.csv --x svd50.rank --y svd50.table:psnr:mean --series svd50.method --plot psnr.svg"
    )]
    Chart(ChartArgs),
    /// Convert a Framework3D saved node tree to a cgnodes graph.
    #[command(after_help = "Example: cgnodes import-f3d GeoNodeSystem.json -o graph.json")]
    ImportF3d {
        /// Framework3D JSON file.
        #[arg(required_unless_present = "list_map")]
        input: Option<PathBuf>,
        /// Output graph file.
        #[arg(short = 'o', long = "output", required_unless_present = "list_map")]
        output: Option<PathBuf>,
        /// JSON file mapping custom Framework3D node names onto cgnodes nodes.
        #[arg(long = "f3d-aliases")]
        aliases: Option<PathBuf>,
        /// Print every node map (built-in, then alias overrides) instead of importing.
        #[arg(long = "list-map", conflicts_with_all = ["input", "output"])]
        list_map: bool,
        /// With --list-map: a Markdown table (as in docs/framework3d.md).
        #[arg(long, requires = "list_map")]
        markdown: bool,
    },
    /// Run a Framework3D project folder: the geometry graph per frame, the stage built by the
    /// composition graph, and the render graph's frames (docs/framework3d.md).
    #[command(
        after_help = "Example: cgnodes f3d-project assets/course/hw9 --frames 0..20 --assets assets/course_hw9 --out out"
    )]
    #[cfg(feature = "render")]
    F3dProject(f3d_project::ProjectArgs),
    /// Print what made a file cgnodes wrote: version, graph hash, node, parameters, frame.
    #[command(after_help = "Example: cgnodes provenance out/arap_cow/layout.png --json")]
    Provenance {
        /// A file written by a cgnodes run.
        file: PathBuf,
        /// Print the record as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Print a shell completion script (bash, zsh, fish, elvish or powershell).
    #[command(
        after_help = "Example: cgnodes completions bash > ~/.local/share/bash-completion/completions/cgnodes"
    )]
    Completions {
        /// The shell.
        shell: clap_complete::Shell,
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

/// `--shard` and `--shards`, shared by `run` (frame blocks) and `sweep` (combinations).
#[derive(clap::Args)]
struct ShardArgs {
    /// Run only shard I of N (I from 0): a block of the frames for `run`, every Nth
    /// combination for `sweep`; `auto` reads it from a Slurm job array or a Kubernetes
    /// Indexed Job (see docs/cluster.md).
    #[arg(long, value_name = "I/N|auto")]
    shard: Option<String>,
    /// Number of shards for `--shard auto` in a Kubernetes Indexed Job (default:
    /// CGNODES_SHARDS); the Job's `completions`.
    #[arg(long, value_name = "N")]
    shards: Option<usize>,
}

impl ShardArgs {
    /// The shard asked for, from the command line and the process environment.
    fn resolve(&self) -> Result<Option<crate::shard::Shard>, crate::shard::ShardError> {
        match (&self.shard, self.shards) {
            (None, None) => Ok(None),
            (None, Some(_)) => Err(crate::shard::ShardError::ShardsAlone),
            (Some(s), n) => crate::shard::Shard::resolve(s, n, |k| std::env::var(k).ok()).map(Some),
        }
    }
}

#[derive(clap::Args)]
struct SweepMergeArgs {
    /// CSV parts written by `cgnodes sweep --shard I/N --csv ...`.
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// CSV file to write (default: stdout).
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Chart to write (.svg or .png).
    #[arg(long)]
    plot: Option<PathBuf>,
    /// The sweep file the parts ran: its chart options (x, y, series, log axes, title) are
    /// the defaults, and the parts' varied parameters and measures must be its own.
    #[arg(long, value_name = "SPEC")]
    sweep: Option<PathBuf>,
    #[command(flatten)]
    chart: SweepChartArgs,
}

/// The chart options `sweep` and `sweep-merge` share; given ones override the sweep file's.
#[derive(clap::Args)]
struct SweepChartArgs {
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
}

impl SweepChartArgs {
    /// Sets `spec`'s chart options: each given option, else `defaults`' (a sweep file's).
    fn apply(&self, spec: &mut crate::sweep::SweepSpec, defaults: &crate::sweep::SweepSpec) {
        let pick = |a: &Option<String>, b: &Option<String>| a.clone().or_else(|| b.clone());
        spec.x = pick(&self.x, &defaults.x);
        spec.y = pick(&self.y, &defaults.y);
        spec.series = pick(&self.series, &defaults.series);
        spec.title = pick(&self.title, &defaults.title);
        spec.log_x = self.log_x || defaults.log_x;
        spec.log_y = self.log_y || defaults.log_y;
    }
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
    #[command(flatten)]
    chart: SweepChartArgs,
    /// Frame range A..B per run.
    #[arg(long)]
    frames: Option<String>,
    /// Output directory for the graph's writers (default: a temporary folder).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Worker threads.
    #[arg(long)]
    threads: Option<usize>,
    /// Most memory one node's buffers may take, e.g. 4G or 512MiB (default: CGNODES_MAX_MEMORY,
    /// else half the physical memory).
    #[arg(long = "max-memory", value_name = "SIZE", value_parser = crate::node::parse_size)]
    max_memory: Option<u64>,
    /// Result cache folder on disk, which shards may share (without it, results are reused
    /// only within this process).
    #[arg(long)]
    cache: Option<PathBuf>,
    #[command(flatten)]
    shard: ShardArgs,
}

/// What `run`, `validate` and `dot` share: the graph and how it is loaded, so the three
/// commands accept (and refuse) the same graphs.
#[derive(clap::Args)]
struct GraphArgs {
    /// Graph file (cgnodes JSON or a Framework3D saved node tree).
    graph: PathBuf,
    /// Set an input literal: NODE.SOCKET=VALUE (repeatable).
    #[arg(long = "set", value_name = "NODE.SOCKET=VALUE")]
    set: Vec<String>,
    /// Further folders searched for input files.
    #[arg(long = "assets")]
    assets: Vec<PathBuf>,
    /// JSON file mapping custom Framework3D node names onto cgnodes nodes.
    #[arg(long = "f3d-aliases")]
    f3d_aliases: Option<PathBuf>,
}

#[derive(clap::Args)]
struct ValidateArgs {
    #[command(flatten)]
    load: GraphArgs,
    /// Only these nodes and what they read from must validate; problems elsewhere are
    /// warnings, as in `run --target` (repeatable).
    #[arg(long = "target", value_name = "NODE")]
    target: Vec<String>,
}

#[derive(clap::Args)]
struct RunArgs {
    #[command(flatten)]
    load: GraphArgs,
    /// Output directory; writer nodes write under it.
    #[arg(long, default_value = "out")]
    out: PathBuf,
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
    /// Size limit of the --cache folder: after the run, the least recently used entries are
    /// removed until it fits (e.g. 500MiB, 2G; 0 = no limit).
    #[arg(long = "cache-size", value_name = "SIZE", default_value = "1GiB", value_parser = run::parse_cache_size)]
    cache_size: u64,
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
    /// Also print each node's status and time, and nodes' debug lines.
    #[arg(long, short)]
    verbose: bool,
    /// Do not write OUT/report.html (the run's graph, statuses, timings and written files).
    #[arg(long = "no-report")]
    no_report: bool,
    /// Most memory one node's buffers may take, e.g. 4G or 512MiB (default: CGNODES_MAX_MEMORY,
    /// else half the physical memory).
    #[arg(long = "max-memory", value_name = "SIZE", value_parser = crate::node::parse_size)]
    max_memory: Option<u64>,
    #[command(flatten)]
    shard: ShardArgs,
    /// After the run, rerun whenever the graph file or a file it reads changes (only what
    /// changed recomputes; an invalid edit prints its errors and waits for the next save).
    #[arg(long, conflicts_with = "shard")]
    watch: bool,
}

/// Runs the command line with `registry` (`nodes::builtin_registry()` plus anything a crate
/// adds). Returns the process exit code.
pub fn main_with(registry: Registry) -> i32 {
    // Ctrl-C and SIGTERM kill plugin processes, remove temporaries and exit 130.
    crate::io::interrupt::install();
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
        Cmd::Run(args) => run::cmd(&registry, args),
        Cmd::Serve(args) => serve::cmd(&registry, args),
        Cmd::Validate(args) => validate::cmd(&registry, &args.load, &args.target),
        Cmd::Nodes { json } => nodes::cmd(&registry, json),
        Cmd::Describe { node_type } => describe::cmd(&registry, &node_type),
        Cmd::Schema { untyped } => schema::cmd(&registry, untyped),
        Cmd::Dot(args) => dot::cmd(&registry, &args),
        Cmd::Sweep(args) => sweep::cmd(&registry, args),
        Cmd::SweepMerge(args) => sweep_merge::cmd(&args),
        Cmd::Chart(args) => chart::cmd(&args),
        Cmd::ImportF3d {
            input,
            output,
            aliases,
            list_map,
            markdown,
        } => match (input, output) {
            (Some(i), Some(o)) if !list_map => {
                import_f3d::cmd(&registry, &i, &o, aliases.as_deref())
            }
            _ => import_f3d::list_map(aliases.as_deref(), markdown),
        },
        #[cfg(feature = "render")]
        Cmd::F3dProject(args) => f3d_project::cmd(&registry, args),
        Cmd::Provenance { file, json } => provenance::cmd(&file, json),
        Cmd::Completions { shell } => {
            use clap::CommandFactory;
            clap_complete::generate(
                shell,
                &mut Cli::command(),
                "cgnodes",
                &mut std::io::stdout(),
            );
            0
        }
    }
}
