//! `cgnodes sweep`: runs a graph for every combination of parameter values, records wall time
//! per node and in total, the measured outputs, and the kind of failure of runs that fail,
//! then writes a CSV and a chart of accuracy against time. Upstream results are reused from
//! the cache between combinations. A sweep file (JSON) makes a sweep reproducible.

use crate::exec::{Executor, NodeStatus, RunOptions};
use crate::f3d::Aliases;
use crate::graph::{self, apply_sets, parse_frames, split_link};
use cgnodes_api::node::FileEnv;
use cgnodes_api::registry::Registry;
use cgnodes_api::types::Value;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

mod output;
pub use output::{to_chart, to_csv, value_text, AxisError};

/// Why a sweep stopped.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// The graph did not load, or the frame range did not parse.
    #[error("{0}")]
    Graph(String),
    /// The temporary output folder could not be made.
    #[error("{0}")]
    TempDir(std::io::Error),
    /// The executor did not start.
    #[error(transparent)]
    Start(#[from] crate::exec::StartError),
    /// A measure could not be read.
    #[error(transparent)]
    Measure(#[from] MeasureError),
    /// An axis of the chart could not be read.
    #[error(transparent)]
    Axis(#[from] AxisError),
    /// The chart was not drawn.
    #[error(transparent)]
    Chart(#[from] crate::chart::ChartError),
    /// The CSV was not written.
    #[error("{}: {source}", path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The provenance of a written file was not recorded.
    #[error("{0}")]
    Record(cgnodes_api::node::ProvenanceError),
}

/// A measure (`node.socket[:column[:summary]]`) that could not be read from a run.
#[derive(Debug, thiserror::Error)]
#[error("measure '{spec}': {problem}")]
pub struct MeasureError {
    /// The measure as given.
    pub spec: String,
    /// What is wrong with it.
    pub problem: MeasureProblem,
}

/// What is wrong with a measure.
#[derive(Debug, thiserror::Error)]
pub enum MeasureProblem {
    #[error("expected NODE.SOCKET")]
    NotALink,
    #[error("no output {node}.{socket}")]
    NoOutput { node: String, socket: String },
    #[error("unknown summary '{0}' (last, first, mean, max, min, sum)")]
    UnknownSummary(String),
    #[error("the table has no column '{column}' (it has {})", have.join(", "))]
    NoColumn { column: String, have: Vec<String> },
    #[error("name a column, NODE.SOCKET:COLUMN")]
    ColumnNeeded,
    #[error("a {0} is not a number or a table")]
    NotNumeric(cgnodes_api::types::SocketType),
}

/// A sweep: which graph, which parameters to vary, what to measure, where to write.
#[derive(Clone, Debug, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SweepSpec {
    /// The graph file (relative to the sweep file).
    pub graph: PathBuf,
    /// Parameters to vary: `{"param": "node.socket", "values": [...]}` in order; every
    /// combination runs.
    #[serde(default)]
    pub vary: Vec<Vary>,
    /// Fixed overrides applied to every run (`node.socket=value`).
    #[serde(default)]
    pub set: Vec<String>,
    /// Runs per combination (timings of repeats re-execute the varied nodes).
    #[serde(default = "one")]
    pub repeat: usize,
    /// Outputs to record: `node.socket`, or for a Table `node.socket:column[:last|mean|max|min|sum]`.
    #[serde(default)]
    pub measure: Vec<String>,
    /// CSV file to write (relative to the sweep file).
    #[serde(default)]
    pub csv: Option<PathBuf>,
    /// Chart to write, `.svg` or `.png` (relative to the sweep file).
    #[serde(default)]
    pub plot: Option<PathBuf>,
    /// X axis: `time` (total wall ms, the default), `time:NODE` (one node's ms), a measure, or
    /// a varied parameter.
    #[serde(default)]
    pub x: Option<String>,
    /// Y axis: a measure (default: the first).
    #[serde(default)]
    pub y: Option<String>,
    /// The varied parameter whose values name the series (default: a varied parameter with
    /// string values, if there is one).
    #[serde(default)]
    pub series: Option<String>,
    /// Logarithmic x axis.
    #[serde(default)]
    pub log_x: bool,
    /// Logarithmic y axis.
    #[serde(default)]
    pub log_y: bool,
    /// Chart title.
    #[serde(default)]
    pub title: Option<String>,
    /// Frame range `A..B` run per combination (simulations); measures are read at the last frame.
    #[serde(default)]
    pub frames: Option<String>,
    /// Output directory for the graph's writers (default: a temporary folder).
    #[serde(default)]
    pub out: Option<PathBuf>,
    /// Most bytes one node's buffers may take (`--max-memory`; default: CGNODES_MAX_MEMORY,
    /// else half the physical memory).
    #[serde(default)]
    pub max_memory: Option<u64>,
    /// Run only this shard's combinations (`--shard I/N`, round robin); the CSV then starts
    /// with the columns `shard`, `combination`, `combinations` that `cgnodes sweep-merge` reads.
    #[serde(skip)]
    pub shard: Option<crate::shard::Shard>,
    /// A result cache folder on disk (`--cache DIR`), which the shards of a sweep may share:
    /// an upstream result one shard computed is read by the others. Without it, results are
    /// reused only between the combinations of one process.
    #[serde(skip)]
    pub cache: Option<PathBuf>,
    /// Told after each run (runs done, runs in total) for `cgnodes sweep`'s progress bar.
    #[serde(skip)]
    pub progress: Option<SweepProgress>,
}

/// A callback told after each run of a sweep: (runs done, runs in total).
#[derive(Clone)]
pub struct SweepProgress(pub std::sync::Arc<dyn Fn(usize, usize) + Send + Sync>);

impl std::fmt::Debug for SweepProgress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("SweepProgress")
    }
}

fn one() -> usize {
    1
}

/// One varied parameter.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Vary {
    /// `node.socket`.
    pub param: String,
    /// Values to try.
    pub values: Vec<serde_json::Value>,
}

/// One run of a sweep.
#[derive(Clone, Debug)]
pub struct SweepRow {
    /// Index of the combination in the whole grid (first varied parameter slowest).
    pub combination: usize,
    /// The varied values, in `vary` order.
    pub values: Vec<serde_json::Value>,
    /// Repeat index.
    pub repeat: usize,
    /// `ok` or `failed`.
    pub ok: bool,
    /// Kind of the first failure (`unstable`, `singular`, `invalid`, ...), empty when ok.
    pub error_kind: String,
    /// Message of the first failure.
    pub error: String,
    /// Total wall time in ms (over all frames).
    pub total_ms: f64,
    /// Wall time per node (0 for cached nodes).
    pub node_ms: BTreeMap<String, f64>,
    /// Measured values (NaN when unavailable).
    pub measures: Vec<f64>,
}

/// Parses `A=v1,v2,...` (`--vary`): values are JSON when they parse, else strings.
pub fn parse_vary(s: &str) -> Result<Vary, String> {
    let (param, vals) = s
        .split_once('=')
        .ok_or_else(|| format!("--vary '{s}': expected NODE.PARAM=v1,v2,..."))?;
    split_link(param).ok_or_else(|| format!("--vary '{s}': expected NODE.PARAM=v1,v2,..."))?;
    let values = split_values(vals)
        .into_iter()
        .map(|v| {
            serde_json::from_str(v.trim())
                .unwrap_or_else(|_| serde_json::Value::String(v.trim().to_string()))
        })
        .collect::<Vec<_>>();
    if values.is_empty() {
        return Err(format!("--vary '{s}': no values"));
    }
    Ok(Vary {
        param: param.to_string(),
        values,
    })
}

/// Splits on commas outside brackets, so `[0,1,2],[1,1,1]` gives two vectors.
fn split_values(s: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let (mut depth, mut start) = (0i32, 0);
    for (i, c) in s.char_indices() {
        match c {
            '[' | '{' => depth += 1,
            ']' | '}' => depth -= 1,
            ',' if depth == 0 => {
                out.push(&s[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    if start < s.len() {
        out.push(&s[start..]);
    }
    out
}

/// Reads one measure from a run's outputs.
pub fn measure(outputs: &crate::exec::RunReport, spec: &str) -> Result<f64, MeasureError> {
    let err = |problem| MeasureError {
        spec: spec.to_string(),
        problem,
    };
    let mut parts = spec.split(':');
    let link = parts.next().unwrap_or_default();
    let (node, socket) = split_link(link).ok_or_else(|| err(MeasureProblem::NotALink))?;
    let v = outputs.output(node, socket).ok_or_else(|| {
        err(MeasureProblem::NoOutput {
            node: node.to_string(),
            socket: socket.to_string(),
        })
    })?;
    let column = parts.next();
    let summary = parts.next().unwrap_or("last");
    match v {
        Value::Float(x) => Ok(*x),
        Value::Int(x) => Ok(*x as f64),
        Value::Bool(b) => Ok(f64::from(u8::from(*b))),
        Value::Table(t) => {
            let col = match column {
                Some(c) => t.column(c).ok_or_else(|| {
                    err(MeasureProblem::NoColumn {
                        column: c.to_string(),
                        have: t.columns.iter().map(|(n, _)| n.clone()).collect(),
                    })
                })?,
                None if t.columns.len() == 1 => &t.columns[0].1,
                None => return Err(err(MeasureProblem::ColumnNeeded)),
            };
            summarize(col, summary).map_err(err)
        }
        Value::List(items) => {
            let nums: Vec<f64> = items
                .iter()
                .filter_map(|x| match x {
                    Value::Float(f) => Some(*f),
                    Value::Int(i) => Some(*i as f64),
                    _ => None,
                })
                .collect();
            summarize(&nums, summary).map_err(err)
        }
        other => Err(err(MeasureProblem::NotNumeric(other.socket_type()))),
    }
}

/// One number from a column: its `last`, `first`, `mean`, `max`, `min` or `sum`.
fn summarize(c: &[f64], summary: &str) -> Result<f64, MeasureProblem> {
    let finite = c.iter().copied();
    Ok(match summary {
        "last" => c.last().copied().unwrap_or(f64::NAN),
        "first" => c.first().copied().unwrap_or(f64::NAN),
        "mean" => finite.clone().sum::<f64>() / c.len().max(1) as f64,
        "max" => finite.fold(f64::NEG_INFINITY, f64::max),
        "min" => finite.fold(f64::INFINITY, f64::min),
        "sum" => finite.sum(),
        other => return Err(MeasureProblem::UnknownSummary(other.to_string())),
    })
}

/// Runs a sweep. `base` is the folder relative paths in the spec resolve against.
pub fn run(
    spec: &SweepSpec,
    base: &Path,
    registry: &Registry,
    threads: Option<usize>,
) -> Result<Vec<SweepRow>, SweepError> {
    let gpath = base.join(&spec.graph);
    let graph = graph::load_with(&gpath, &Aliases::default(), registry)
        .map_err(|e| SweepError::Graph(e.to_string()))?;
    let frames = match &spec.frames {
        Some(f) => parse_frames(f).map_err(SweepError::Graph)?,
        None => graph.spec.frames_hint().unwrap_or((0, 0)),
    };
    // Registered so that Ctrl-C removes it (`io::interrupt`).
    let (_tracked, tmp) = cgnodes_api::io::interrupt::track(tempfile::tempdir, |t| {
        cgnodes_api::io::interrupt::Resource::Path(t.path().to_path_buf())
    })
    .map_err(SweepError::TempDir)?;
    let sweep = Sweep {
        spec,
        registry,
        graph,
        frames,
        out_dir: spec
            .out
            .as_ref()
            .map(|o| base.join(o))
            .unwrap_or_else(|| tmp.path().to_path_buf()),
        exec: Executor::new(threads, spec.cache.as_deref())?,
        varied_nodes: spec
            .vary
            .iter()
            .filter_map(|v| split_link(&v.param).map(|(n, _)| n.to_string()))
            .collect(),
    };
    let combos = combinations(&spec.vary);
    let mut rows = Vec::new();
    let shard = spec.shard.unwrap_or_default();
    let total_runs = (0..combos.len()).filter(|&ci| shard.takes(ci)).count() * spec.repeat.max(1);
    let tell = |done: usize| {
        if let Some(p) = &spec.progress {
            (p.0)(done, total_runs);
        }
    };
    tell(0);
    for (ci, combo) in combos.iter().enumerate() {
        if !shard.takes(ci) {
            continue;
        }
        for rep in 0..spec.repeat.max(1) {
            rows.push(sweep.run_one(ci, combo, rep)?);
            tell(rows.len());
        }
    }
    Ok(rows)
}

/// The cartesian product of the varied values, the first parameter slowest.
fn combinations(vary: &[Vary]) -> Vec<Vec<serde_json::Value>> {
    let mut combos: Vec<Vec<serde_json::Value>> = vec![Vec::new()];
    for v in vary {
        combos = combos
            .into_iter()
            .flat_map(|c| {
                v.values.iter().map(move |x| {
                    let mut c = c.clone();
                    c.push(x.clone());
                    c
                })
            })
            .collect();
    }
    combos
}

/// Why one combination's graph is invalid (a failed row, not a failed sweep).
#[derive(Debug, thiserror::Error)]
enum Invalid {
    /// An override does not apply.
    #[error(transparent)]
    Set(crate::graph::overrides::SetError),
    /// The first validation error.
    #[error(transparent)]
    Graph(Box<crate::validate::GraphError>),
}

/// What every run of a sweep shares.
struct Sweep<'a> {
    spec: &'a SweepSpec,
    registry: &'a Registry,
    graph: graph::Graph,
    frames: (i64, i64),
    out_dir: PathBuf,
    exec: Executor,
    /// The nodes whose parameters vary (re-executed by repeats, for their timings).
    varied_nodes: Vec<String>,
}

impl Sweep<'_> {
    /// Repeat `rep` of combination `ci`: a failed row when the graph is invalid with these
    /// values or a node fails, else the timings and the measures.
    fn run_one(
        &self,
        ci: usize,
        combo: &[serde_json::Value],
        rep: usize,
    ) -> Result<SweepRow, SweepError> {
        let mut row = SweepRow {
            combination: ci,
            values: combo.to_vec(),
            repeat: rep,
            ok: true,
            error_kind: String::new(),
            error: String::new(),
            total_ms: 0.0,
            node_ms: BTreeMap::new(),
            measures: vec![f64::NAN; self.spec.measure.len()],
        };
        let valid = match self.validate(combo) {
            Ok(v) => v,
            Err(e) => {
                row.ok = false;
                row.error_kind = "invalid".into();
                row.error = e.to_string();
                return Ok(row);
            }
        };
        let last = self.run_frames(&valid, rep, &mut row);
        if let (true, Some(r)) = (row.ok, &last) {
            for (k, m) in self.spec.measure.iter().enumerate() {
                row.measures[k] = measure(r, m)?;
            }
        }
        Ok(row)
    }

    /// The graph with the fixed and the varied values set, validated.
    fn validate(
        &self,
        combo: &[serde_json::Value],
    ) -> Result<crate::validate::ValidGraph, Invalid> {
        let mut g = self.graph.clone();
        let mut sets = self.spec.set.clone();
        for (v, x) in self.spec.vary.iter().zip(combo) {
            sets.push(format!("{}={}", v.param, value_text(x)));
        }
        apply_sets(&mut g, &sets).map_err(Invalid::Set)?;
        crate::validate::validate(&g, self.registry)
            .map_err(|mut e| Invalid::Graph(Box::new(e.remove(0))))
    }

    /// Run options of repeat `rep`: the measured outputs are read after the run, so their
    /// nodes run even when the graph's outputs do not need them (a metric node is usually no
    /// writer), and they compute those outputs even when nothing links them.
    fn options(&self, valid: &crate::validate::ValidGraph, rep: usize) -> RunOptions {
        RunOptions {
            files: FileEnv {
                graph_dir: valid.dir.clone(),
                out_dir: self.out_dir.clone(),
                ..Default::default()
            },
            read_outputs: self
                .spec
                .measure
                .iter()
                .filter_map(|m| m.split(':').next().map(str::to_string))
                .collect(),
            max_memory: self.spec.max_memory,
            recompute: if rep > 0 {
                self.varied_nodes.clone()
            } else {
                Vec::new()
            },
            ..Default::default()
        }
    }

    /// Runs every frame, adding the wall times to `row` and marking it failed at the first
    /// failure that counts; returns the last frame's report when every frame ran.
    fn run_frames(
        &self,
        valid: &crate::validate::ValidGraph,
        rep: usize,
        row: &mut SweepRow,
    ) -> Option<crate::exec::RunReport> {
        let opts = self.options(valid, rep);
        let (f0, f1) = self.frames;
        self.exec.reset_states();
        // Before the last frame, only failures of the simulations and what they read end
        // the run: a node that feeds no stateful node (a metric over a series that is
        // still too short, say) runs again at the last frame, where it counts.
        let stateful: Vec<usize> = (0..valid.nodes.len())
            .filter(|&i| valid.nodes[i].decl.stateful)
            .collect();
        let feeds_state = valid.needed(&stateful);
        let mut last = None;
        for f in f0..=f1 {
            let r = self.exec.run(valid, &opts, f);
            row.total_ms += r.total_ms;
            for n in &r.nodes {
                *row.node_ms.entry(n.id.clone()).or_default() +=
                    if matches!(n.status, NodeStatus::Ran) {
                        n.ms
                    } else {
                        0.0
                    };
            }
            let counts = |id: &str| f == f1 || valid.index.get(id).is_some_and(|&i| feeds_state[i]);
            let failed = r.nodes.iter().find_map(|n| match &n.status {
                NodeStatus::Failed(e) if counts(&n.id) => Some((
                    e.kind.to_string(),
                    format!("{} ({}): {e}", n.id, n.node_type),
                )),
                _ => None,
            });
            if let Some((kind, msg)) = failed {
                row.ok = false;
                row.error_kind = kind;
                row.error = format!("frame {f}: {msg}");
                return None;
            }
            last = Some(r);
        }
        last
    }
}

/// Runs a sweep and writes its CSV and chart; returns the rows.
pub fn run_and_write(
    spec: &SweepSpec,
    base: &Path,
    registry: &Registry,
    threads: Option<usize>,
) -> Result<Vec<SweepRow>, SweepError> {
    let rows = run(spec, base, registry, threads)?;
    let record = sweep_provenance(spec, base);
    if let Some(csv) = &spec.csv {
        let p = base.join(csv);
        let text = to_csv(spec, &rows);
        cgnodes_api::io::write_atomic(&p, |w| w.write_all(text.as_bytes())).map_err(|source| {
            SweepError::Write {
                path: p.clone(),
                source,
            }
        })?;
        record.record_in(&p).map_err(SweepError::Record)?;
    }
    if let Some(plot) = &spec.plot {
        let p = base.join(plot);
        crate::chart::draw(&to_chart(spec, &rows)?, &p)?;
        record.record_in(&p).map_err(SweepError::Record)?;
    }
    Ok(rows)
}

/// What made a sweep's CSV and chart: the graph (path and hash), node `sweep`, and as
/// parameters the sweep's `vary`, `set`, `measure`, `frames`, `repeat` and shard.
fn sweep_provenance(spec: &SweepSpec, base: &Path) -> cgnodes_api::node::Provenance {
    let gpath = base.join(&spec.graph);
    let mut params = std::collections::BTreeMap::new();
    let json = |v: Result<serde_json::Value, serde_json::Error>| v.unwrap_or_default();
    params.insert("vary".into(), json(serde_json::to_value(&spec.vary)));
    params.insert("set".into(), json(serde_json::to_value(&spec.set)));
    params.insert("measure".into(), json(serde_json::to_value(&spec.measure)));
    params.insert("frames".into(), json(serde_json::to_value(&spec.frames)));
    params.insert("repeat".into(), serde_json::Value::from(spec.repeat));
    params.insert(
        "shard".into(),
        serde_json::Value::from(spec.shard.map(|s| s.to_string())),
    );
    cgnodes_api::node::Provenance {
        cgnodes: env!("CARGO_PKG_VERSION").into(),
        graph: gpath.display().to_string(),
        graph_hash: std::fs::read(&gpath)
            .map(|b| cgnodes_api::node::Provenance::hash_graph(&b))
            .unwrap_or_default(),
        node: "sweep".into(),
        node_type: "cgnodes sweep".into(),
        params,
        frame: spec
            .frames
            .as_deref()
            .and_then(|f| parse_frames(f).ok())
            .map_or(0, |(_, b)| b),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vary_values_parse_as_json_or_strings() {
        let v = parse_vary("t.weights=uniform,cotangent").unwrap();
        assert_eq!(
            v.values,
            vec![serde_json::json!("uniform"), serde_json::json!("cotangent")]
        );
        let v = parse_vary("c.eye=[0,1,2],[3,4,5]").unwrap();
        assert_eq!(v.values.len(), 2);
        let v = parse_vary("s.h=0.01,0.02").unwrap();
        assert_eq!(v.values[1], serde_json::json!(0.02));
        assert!(parse_vary("nodot=1").is_err());
    }
}
