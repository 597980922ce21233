//! The graph `serve` keeps live: one executor (so a rerun recomputes only what changed), the
//! last run's state as the page reads it (`/api/state`), and the event streams of open
//! pages (`/api/events`).

use crate::exec::{Executor, RunOptions};
use crate::f3d::Aliases;
use crate::graph::{self, GraphFile};
use crate::node::{FileEnv, LogLevel};
use crate::registry::Registry;
use crate::report::{graph_svg::graph_svg, Collector, Status};
use crate::validate::{validate_with, InputSource, ValidGraph};
use serde_json::{json, Value as Json};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::mpsc::Sender;
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Log lines kept per node for the page.
const LOG_LINES: usize = 40;

/// What `serve` was started with.
pub struct Setup {
    /// The graph file.
    pub graph: PathBuf,
    /// `--out`.
    pub out: PathBuf,
    /// `--assets`.
    pub assets: Vec<PathBuf>,
    /// `--frames` (else the graph's own range, else frame 0).
    pub frames: Option<(i64, i64)>,
    /// `--f3d-aliases`.
    pub aliases: Aliases,
}

/// The live graph.
pub struct Session<'r> {
    registry: &'r Registry,
    /// The start options.
    pub setup: Setup,
    exec: Executor,
    state: Mutex<State>,
    subscribers: Subscribers,
}

/// The event streams of open pages.
type Subscribers = Arc<Mutex<Vec<Sender<String>>>>;

/// Sends `data` as event `name` to every stream in `subs`, dropping closed ones.
fn broadcast_to(subs: &Subscribers, name: &str, data: &Json) {
    let msg = format!("event: {name}\ndata: {data}\n\n");
    subs.lock()
        .unwrap_or_else(|e| e.into_inner())
        .retain(|tx| tx.send(msg.clone()).is_ok());
}

/// The last run as the page sees it.
#[derive(Default)]
struct State {
    version: u64,
    /// `/api/state`'s body.
    json: String,
    /// The graph file's text at the last run.
    text: String,
    /// The files the last valid graph reads.
    inputs: Vec<PathBuf>,
    /// The last valid graph's drawing (kept while an edit is invalid).
    svg: String,
    /// The text the page last wrote into the graph file (its run is already queued).
    written: Option<String>,
}

impl<'r> Session<'r> {
    /// A session for `setup`, with an executor of `threads` workers.
    pub fn new(
        registry: &'r Registry,
        setup: Setup,
        threads: Option<usize>,
    ) -> Result<Session<'r>, crate::exec::StartError> {
        Ok(Session {
            registry,
            setup,
            exec: Executor::new(threads, None)?,
            state: Mutex::default(),
            subscribers: Subscribers::default(),
        })
    }

    /// A new event stream: every event from now on, as SSE text.
    pub fn subscribe(&self, tx: Sender<String>) {
        self.subscribers
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(tx);
    }

    /// Sends `data` as event `name` to every open page, dropping closed ones.
    pub fn broadcast(&self, name: &str, data: &Json) {
        broadcast_to(&self.subscribers, name, data);
    }

    /// `/api/state`'s body.
    pub fn state_json(&self) -> String {
        let st = self.lock();
        if st.json.is_empty() {
            // Before the first run ends.
            return json!({ "version": 0, "ok": true, "ms": 0.0, "svg": "", "error": Json::Null,
                           "nodes": [] })
            .to_string();
        }
        st.json.clone()
    }

    /// The graph file's text at the last run.
    pub fn text(&self) -> String {
        self.lock().text.clone()
    }

    /// The files the last valid graph reads (the page may read these, the graph file and
    /// `--out`, nothing else).
    pub fn inputs(&self) -> Vec<PathBuf> {
        self.lock().inputs.clone()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The node types.
    pub fn registry(&self) -> &Registry {
        self.registry
    }

    /// Remembers that the page wrote `text` into the graph file, so the file watch does not
    /// run it a second time.
    pub fn note_written(&self, text: &str) {
        self.lock().written = Some(text.to_string());
    }

    /// Whether the graph file's text differs from the last run's and from what the page
    /// wrote itself.
    pub fn text_changed(&self) -> bool {
        let now = std::fs::read_to_string(&self.setup.graph).ok();
        let st = self.lock();
        now.as_ref() != Some(&st.text) && now != st.written
    }

    /// Loads, validates and runs the graph; the state and the pages are updated.
    pub fn run(&self) {
        let t0 = Instant::now();
        let version = self.lock().version + 1;
        self.broadcast("run", &json!({ "version": version }));
        let text = std::fs::read_to_string(&self.setup.graph).unwrap_or_default();
        let outcome = self.load_and_run(version);
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let mut st = self.lock();
        st.version = version;
        st.text = text;
        // The page's own write has run now; the same text saved again later is a change.
        st.written = None;
        let state = match outcome {
            Outcome::Unreadable(e) => {
                // The last good state stays, with the error on top.
                let mut v: Json = serde_json::from_str(&st.json).unwrap_or_else(|_| json!({}));
                v["error"] = json!(e);
                v["version"] = json!(version);
                v["ms"] = json!(ms);
                v
            }
            Outcome::Invalid {
                spec,
                errors,
                graph_errors,
            } => {
                let nodes = spec_nodes(self.registry, &spec, &errors);
                json!({ "version": version, "file": self.setup.graph.display().to_string(),
                        "error": graph_errors.join("\n"), "ms": ms, "svg": st.svg,
                        "nodes": nodes, "ok": false })
            }
            Outcome::Ran {
                graph,
                collected,
                logs,
                inputs,
            } => {
                let status = |i: usize| {
                    collected
                        .nodes
                        .get(&graph.nodes[i].id)
                        .and_then(|n| n.status)
                        .unwrap_or(Status::Skipped)
                };
                st.svg = graph_svg(&graph, &status);
                st.inputs = inputs;
                let ok = collected
                    .nodes
                    .values()
                    .all(|n| !matches!(n.status, Some(Status::Failed) | Some(Status::Blocked)));
                json!({ "version": version, "file": self.setup.graph.display().to_string(),
                        "error": Json::Null, "ms": ms, "svg": st.svg, "ok": ok,
                        "frames": collected.frames,
                        "nodes": self.run_nodes(&graph, &collected, &logs, version) })
            }
        };
        st.json = state.to_string();
        drop(st);
        self.broadcast("done", &json!({ "version": version, "ms": ms }));
    }

    fn load_and_run(&self, version: u64) -> Outcome {
        let g = match graph::load_with(&self.setup.graph, &self.setup.aliases, self.registry) {
            Ok(g) => g,
            Err(e) => return Outcome::Unreadable(e.to_string()),
        };
        let valid = match validate_with(&g, self.registry, &self.setup.assets) {
            Ok(v) => v,
            Err(errs) => {
                let mut errors: BTreeMap<String, Vec<String>> = BTreeMap::new();
                let mut graph_errors = Vec::new();
                for e in errs {
                    match e.node() {
                        Some(n) => errors.entry(n.to_string()).or_default().push(e.to_string()),
                        None => graph_errors.push(e.to_string()),
                    }
                }
                return Outcome::Invalid {
                    spec: g.spec,
                    errors,
                    graph_errors,
                };
            }
        };
        let files = FileEnv {
            graph_dir: valid.dir.clone(),
            asset_dirs: self.setup.assets.clone(),
            out_dir: self.setup.out.clone(),
            allow_write_anywhere: false,
        };
        let inputs = crate::exec::input_files(&valid, &files);
        let (f0, f1) = self.setup.frames.or(g.spec.frames_hint()).unwrap_or((0, 0));
        // Log lines and progress stream to the pages as nodes write them.
        let subs = self.subscribers.clone();
        let log: crate::node::LogFn = Arc::new(move |node: &str, level: LogLevel, line: &str| {
            broadcast_to(
                &subs,
                "log",
                &json!({ "version": version, "node": node, "level": level_name(level), "line": line }),
            );
        });
        let subs = self.subscribers.clone();
        let progress: crate::node::ProgressFn = Arc::new(move |node: &str, f: f64| {
            broadcast_to(&subs, "progress", &json!({ "node": node, "fraction": f }));
        });
        let opts = RunOptions {
            targets: None,
            files,
            progress: Some(progress),
            log: Some(log),
            measure_memory: false,
            recompute: Vec::new(),
            read_outputs: Vec::new(),
            all_outputs: false,
            max_memory: None,
        };
        // Simulations start again from the first frame on every run.
        self.exec.reset_states();
        let mut collected = Collector::default();
        let mut logs: BTreeMap<String, Vec<String>> = BTreeMap::new();
        for frame in f0..=f1 {
            let report = self.exec.run(&valid, &opts, frame);
            for n in &report.nodes {
                let kept = logs.entry(n.id.clone()).or_default();
                kept.extend(n.logs.iter().cloned());
                let extra = kept.len().saturating_sub(LOG_LINES);
                kept.drain(..extra);
            }
            collected.add(&report);
        }
        Outcome::Ran {
            graph: valid,
            collected,
            logs,
            inputs,
        }
    }

    /// Each node of a run: status, time, error, parameters and files.
    fn run_nodes(
        &self,
        g: &ValidGraph,
        c: &Collector,
        logs: &BTreeMap<String, Vec<String>>,
        version: u64,
    ) -> Vec<Json> {
        g.nodes
            .iter()
            .map(|n| {
                let s = c.nodes.get(&n.id);
                let params: Vec<Json> = n
                    .inputs
                    .iter()
                    .filter_map(|(name, src)| {
                        let decl = n.decl.input(name)?;
                        let (value, linked, set) = match src {
                            InputSource::Literal(v) => (v.to_json(), Json::Null, true),
                            InputSource::Default(v) => (v.to_json(), Json::Null, false),
                            InputSource::Links(ls) => (
                                None,
                                json!(ls
                                    .iter()
                                    .map(|(j, o)| format!("{}.{o}", g.nodes[*j].id))
                                    .collect::<Vec<_>>()),
                                false,
                            ),
                            InputSource::Unset => (None, Json::Null, false),
                        };
                        param_json(decl, value.unwrap_or(Json::Null), set, linked)
                    })
                    .collect();
                let files: Vec<Json> = s
                    .map(|s| {
                        s.written
                            .iter()
                            .filter_map(|p| self.file_entry(p, version))
                            .collect()
                    })
                    .unwrap_or_default();
                json!({
                    "id": n.id, "type": n.decl.type_name, "doc": n.decl.doc,
                    "status": s.and_then(|s| s.status).unwrap_or(Status::Skipped).name(),
                    "ms": s.map_or(0.0, |s| s.ms),
                    "ran": s.map_or(0, |s| s.ran), "cached": s.map_or(0, |s| s.cached),
                    "error": s.and_then(|s| s.error.clone()),
                    "errors": Vec::<String>::new(),
                    "params": params, "files": files,
                    "logs": logs.get(&n.id).cloned().unwrap_or_default(),
                })
            })
            .collect()
    }

    /// A written file as the page links it: its path under `--out`, its kind, the version.
    fn file_entry(&self, p: &Path, version: u64) -> Option<Json> {
        let rel = p.strip_prefix(&self.setup.out).ok()?;
        let rel = rel.to_string_lossy().replace('\\', "/");
        if rel.starts_with("report") {
            return None;
        }
        let ext = p
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        let kind = match ext.as_str() {
            "png" | "jpg" | "jpeg" | "bmp" | "gif" | "webp" => "image",
            "obj" | "ply" | "off" | "usda" | "stl" => "mesh",
            "svg" => "svg",
            "csv" => "table",
            "mtl" | "json" => return None,
            _ => "file",
        };
        // The file's modification time versions its URL: a file a rerun did not touch keeps
        // its URL and the browser's copy.
        let stamp = std::fs::metadata(p)
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map_or(version as u128, |d| d.as_nanos());
        Some(
            json!({ "path": rel, "kind": kind, "stamp": stamp.to_string(),
                     "url": format!("/files/{}?v={stamp}", url_path(&rel)) }),
        )
    }
}

/// What loading and running gave.
enum Outcome {
    /// The file could not be read or parsed.
    Unreadable(String),
    /// It parsed but did not validate: errors by node id, and errors of the whole graph.
    Invalid {
        spec: GraphFile,
        errors: BTreeMap<String, Vec<String>>,
        graph_errors: Vec<String>,
    },
    /// It ran.
    Ran {
        graph: ValidGraph,
        collected: Collector,
        /// The last log lines of each node.
        logs: BTreeMap<String, Vec<String>>,
        inputs: Vec<PathBuf>,
    },
}

/// The nodes of a graph that did not validate, as the file gives them, with their errors and
/// the parameters their types declare.
fn spec_nodes(
    registry: &Registry,
    spec: &GraphFile,
    errors: &BTreeMap<String, Vec<String>>,
) -> Vec<Json> {
    spec.nodes
        .iter()
        .map(|(id, n)| {
            let decl = registry.get(&n.node_type);
            let params: Vec<Json> = decl
                .map(|d| {
                    d.inputs
                        .iter()
                        .filter_map(|s| {
                            let lit = n.params.get(&s.name);
                            let value = lit.cloned().or(s.default.clone()).unwrap_or(Json::Null);
                            let linked = n
                                .inputs
                                .get(&s.name)
                                .map_or(Json::Null, |l| json!(l.links()));
                            param_json(s, value, lit.is_some(), linked)
                        })
                        .collect()
                })
                .unwrap_or_default();
            let errs = errors.get(id).cloned().unwrap_or_default();
            json!({
                "id": id, "type": n.node_type, "doc": decl.map(|d| d.doc.clone()),
                "status": if errs.is_empty() { "skipped" } else { "failed" },
                "ms": 0.0, "ran": 0, "cached": 0, "error": Json::Null, "errors": errs,
                "params": params, "files": [],
            })
        })
        .collect()
}

/// A parameter as the page's widgets read it: the socket's declaration (type, default, range,
/// choices), its value, whether the file sets it, and its links (`null` when literal).
fn param_json(s: &crate::node::SocketDecl, value: Json, set: bool, linked: Json) -> Option<Json> {
    let mut p = serde_json::to_value(s).ok()?;
    p["value"] = value;
    p["set"] = json!(set);
    p["linked"] = linked;
    Some(p)
}

/// `rel` with each segment percent-encoded for a URL path.
fn url_path(rel: &str) -> String {
    rel.split('/')
        .map(|seg| {
            seg.bytes()
                .map(|b| {
                    if b.is_ascii_alphanumeric() || b"-_.~".contains(&b) {
                        (b as char).to_string()
                    } else {
                        format!("%{b:02X}")
                    }
                })
                .collect::<String>()
        })
        .collect::<Vec<_>>()
        .join("/")
}

/// Decodes `%XX` escapes (and `+` is kept as is); `None` on a bad escape or non-UTF-8.
pub fn url_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let h = std::str::from_utf8(b.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(h, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// The level name the page shows for a log line.
pub fn level_name(l: LogLevel) -> &'static str {
    match l {
        LogLevel::Debug => "debug",
        LogLevel::Info => "info",
        LogLevel::Warning => "warning",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn url_paths_round_trip() {
        let p = "implicit/cloth 0001 #a%.obj";
        let e = url_path(p);
        assert_eq!(e, "implicit/cloth%200001%20%23a%25.obj");
        assert_eq!(url_decode(&e).as_deref(), Some(p));
        assert_eq!(url_decode("%zz"), None);
    }
}
