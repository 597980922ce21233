//! The scheduler: runs the nodes that the requested outputs need, in parallel where branches
//! are independent, serving unchanged nodes from the caches and keeping simulation state
//! between frames.

use crate::cache::{DiskCache, Entry, Key, MemoryCache};
use crate::node::{ErrorKind, ExecContext, FileEnv, FileRole, NodeError, ProgressFn};
use crate::types::{SocketType, Value};
use crate::validate::{InputSource, ValidGraph};
use std::any::Any;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// How a run is done.
#[derive(Clone, Default)]
pub struct RunOptions {
    /// Node ids to evaluate instead of the graph's `outputs` (`--target`).
    pub targets: Option<Vec<String>>,
    /// Where files are read and written.
    pub files: FileEnv,
    /// Progress callback for long nodes.
    pub progress: Option<ProgressFn>,
    /// Record resident memory after each node (for `--profile`; costs a /proc read per node).
    pub measure_memory: bool,
    /// Node ids that must run even when cached, with everything downstream of them
    /// (`cgnodes sweep --repeat` times real executions this way).
    pub recompute: Vec<String>,
    /// Outputs the caller reads from the report after the run, as `NODE.SOCKET` (or `NODE`
    /// for all of a node's outputs). Their nodes run as if they were targets, and these
    /// outputs are computed even when nothing in the graph reads them: nodes may skip the
    /// outputs no one wants (`ExecContext::output_wanted`).
    pub read_outputs: Vec<String>,
    /// Every node that runs computes all its outputs, wanted or not.
    pub all_outputs: bool,
}

/// What happened to one node in a run.
#[derive(Clone, Debug)]
pub enum NodeStatus {
    /// It ran.
    Ran,
    /// Its result came from the memory or disk cache.
    Cached,
    /// No requested output needs it.
    Skipped,
    /// It failed.
    Failed(NodeError),
    /// It could not run because a node it reads from failed.
    Blocked {
        /// The failed node upstream.
        by: String,
    },
}

/// One node's part of a run.
#[derive(Clone, Debug)]
pub struct NodeReport {
    /// Node id.
    pub id: String,
    /// Node type.
    pub node_type: String,
    /// What happened.
    pub status: NodeStatus,
    /// Wall time in milliseconds (0 when not run).
    pub ms: f64,
    /// Resident memory of the process when it finished, in KiB (0 when unknown).
    pub rss_kib: u64,
    /// Log lines.
    pub logs: Vec<String>,
    /// Files written.
    pub written: Vec<PathBuf>,
}

/// The result of running a graph once (one frame).
#[derive(Clone, Debug)]
pub struct RunReport {
    /// The graph file.
    pub file: PathBuf,
    /// The frame.
    pub frame: i64,
    /// Every node in topological order.
    pub nodes: Vec<NodeReport>,
    /// Outputs of every node that ran or was cached. A node that is no target may leave out
    /// outputs nothing reads (`ExecContext::output_wanted`): name the ones you read in
    /// `RunOptions::read_outputs`.
    pub outputs: HashMap<String, Arc<BTreeMap<String, Value>>>,
    /// Total wall time in milliseconds.
    pub total_ms: f64,
    /// Peak resident memory of the process in KiB (0 when unknown).
    pub peak_rss_kib: u64,
}

impl RunReport {
    /// Whether no node failed.
    pub fn ok(&self) -> bool {
        !self
            .nodes
            .iter()
            .any(|n| matches!(n.status, NodeStatus::Failed(_) | NodeStatus::Blocked { .. }))
    }
    /// The value of `node.socket`, if computed.
    pub fn output(&self, node: &str, socket: &str) -> Option<&Value> {
        self.outputs.get(node)?.get(socket)
    }
    /// The report of node `id`.
    pub fn node(&self, id: &str) -> Option<&NodeReport> {
        self.nodes.iter().find(|n| n.id == id)
    }
    /// Ids of the nodes that ran (not cached, skipped or failed).
    pub fn executed(&self) -> Vec<&str> {
        self.nodes
            .iter()
            .filter(|n| matches!(n.status, NodeStatus::Ran))
            .map(|n| n.id.as_str())
            .collect()
    }
    /// Error messages of failed nodes, each naming the file, node id and type.
    pub fn errors(&self) -> Vec<String> {
        self.nodes
            .iter()
            .filter_map(|n| match &n.status {
                NodeStatus::Failed(e) => Some(format!(
                    "{}: node '{}' ({}) failed [{}]: {}",
                    self.file.display(),
                    n.id,
                    n.node_type,
                    e.kind,
                    e
                )),
                NodeStatus::Blocked { by } => Some(format!(
                    "{}: node '{}' ({}) did not run because '{by}' failed",
                    self.file.display(),
                    n.id,
                    n.node_type
                )),
                _ => None,
            })
            .collect()
    }
}

/// Runs graphs. Holds the caches, the simulation state of stateful nodes (by node id) and the
/// thread pool, so repeated runs (frames, sweeps) reuse what did not change.
pub struct Executor {
    pool: rayon::ThreadPool,
    memory: Mutex<MemoryCache>,
    disk: Option<DiskCache>,
    states: Mutex<HashMap<String, Box<dyn Any + Send>>>,
}

type Slot = Mutex<Option<Result<Arc<BTreeMap<String, Value>>, String>>>;

impl Executor {
    /// An executor with `threads` worker threads (all cores when `None`) and an optional
    /// disk cache.
    pub fn new(
        threads: Option<usize>,
        cache_dir: Option<&std::path::Path>,
    ) -> Result<Executor, String> {
        let mut b = rayon::ThreadPoolBuilder::new();
        if let Some(n) = threads {
            b = b.num_threads(n.max(1));
        }
        let pool = b
            .build()
            .map_err(|e| format!("cannot start threads: {e}"))?;
        let disk = match cache_dir {
            Some(d) => {
                Some(DiskCache::open(d).map_err(|e| format!("cache folder {}: {e}", d.display()))?)
            }
            None => None,
        };
        Ok(Executor {
            pool,
            memory: Mutex::new(MemoryCache::default()),
            disk,
            states: Mutex::new(HashMap::new()),
        })
    }

    /// Drops the state of every stateful node (simulations restart).
    pub fn reset_states(&self) {
        self.states
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clear();
    }

    /// Runs `graph` for one frame.
    pub fn run(&self, graph: &ValidGraph, opts: &RunOptions, frame: i64) -> RunReport {
        let start = Instant::now();
        self.memory
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .next_generation();
        let targets: Vec<usize> = match &opts.targets {
            Some(t) => t
                .iter()
                .filter_map(|id| graph.index.get(id).copied())
                .collect(),
            None => graph.targets.clone(),
        };
        let n = graph.nodes.len();
        // Which outputs each node must produce: `None` = all of them (targets, and outputs
        // the caller reads whole); else the sockets linked by needed nodes or read by name.
        let mut wanted: Vec<Option<BTreeSet<String>>> = vec![Some(BTreeSet::new()); n];
        let mut roots = targets.clone();
        for &t in &targets {
            wanted[t] = None;
        }
        for r in &opts.read_outputs {
            let (id, socket) = match r.split_once('.') {
                Some((id, socket)) => (id, Some(socket)),
                None => (r.as_str(), None),
            };
            let Some(&i) = graph.index.get(id) else {
                continue;
            };
            roots.push(i);
            match (socket, &mut wanted[i]) {
                (None, w) => *w = None,
                (Some(sock), Some(w)) => {
                    w.insert(sock.to_string());
                }
                (Some(_), None) => {}
            }
        }
        let need = graph.needed(&roots);
        for (j, node) in graph.nodes.iter().enumerate() {
            if !need[j] {
                continue;
            }
            for (_, src) in &node.inputs {
                if let InputSource::Links(links) = src {
                    for (j, out) in links {
                        if let Some(w) = &mut wanted[*j] {
                            w.insert(out.clone());
                        }
                    }
                }
            }
        }
        if opts.all_outputs {
            wanted.iter_mut().for_each(|w| *w = None);
        }
        let keys = cache_keys(graph, &need, &opts.files, frame);
        let mut fresh = vec![false; n];
        for (i, node) in graph.nodes.iter().enumerate() {
            fresh[i] = opts.recompute.contains(&node.id) || node.deps.iter().any(|&d| fresh[d]);
        }
        let slots: Vec<Slot> = (0..n).map(|_| Mutex::new(None)).collect();
        let reports: Vec<Mutex<Option<NodeReport>>> = (0..n).map(|_| Mutex::new(None)).collect();
        // Dependents and pending counts over the needed subgraph.
        let mut dependents: Vec<Vec<usize>> = vec![Vec::new(); n];
        let pending: Vec<AtomicUsize> = (0..n).map(|_| AtomicUsize::new(0)).collect();
        for (i, node) in graph.nodes.iter().enumerate() {
            if !need[i] {
                continue;
            }
            pending[i].store(node.deps.len(), Ordering::Relaxed);
            for &d in &node.deps {
                dependents[d].push(i);
            }
        }
        let shared = Shared {
            graph,
            opts,
            frame,
            keys: &keys,
            fresh: &fresh,
            wanted: &wanted,
            slots: &slots,
            reports: &reports,
            dependents: &dependents,
            pending: &pending,
        };
        self.pool.install(|| {
            rayon::scope(|s| {
                for (i, node) in graph.nodes.iter().enumerate() {
                    if need[i] && node.deps.is_empty() {
                        let sh = &shared;
                        s.spawn(move |s| self.run_node(s, sh, i));
                    }
                }
            })
        });
        let mut nodes = Vec::with_capacity(n);
        let mut outputs = HashMap::new();
        for (i, node) in graph.nodes.iter().enumerate() {
            let r = reports[i].lock().unwrap_or_else(|p| p.into_inner()).take();
            nodes.push(r.unwrap_or_else(|| NodeReport {
                id: node.id.clone(),
                node_type: node.decl.type_name.clone(),
                status: NodeStatus::Skipped,
                ms: 0.0,
                rss_kib: 0,
                logs: Vec::new(),
                written: Vec::new(),
            }));
            if let Some(Ok(o)) = slots[i].lock().unwrap_or_else(|p| p.into_inner()).take() {
                outputs.insert(node.id.clone(), o);
            }
        }
        RunReport {
            file: graph.file.clone(),
            frame,
            nodes,
            outputs,
            total_ms: start.elapsed().as_secs_f64() * 1e3,
            peak_rss_kib: read_status_kib("VmHWM:"),
        }
    }

    fn run_node<'s>(&'s self, scope: &rayon::Scope<'s>, sh: &'s Shared<'s>, i: usize) {
        let node = &sh.graph.nodes[i];
        let t0 = Instant::now();
        let mut report = NodeReport {
            id: node.id.clone(),
            node_type: node.decl.type_name.clone(),
            status: NodeStatus::Ran,
            ms: 0.0,
            rss_kib: 0,
            logs: Vec::new(),
            written: Vec::new(),
        };
        let result = self.evaluate(sh, i, &mut report);
        report.ms = t0.elapsed().as_secs_f64() * 1e3;
        if sh.opts.measure_memory {
            report.rss_kib = read_status_kib("VmRSS:");
        }
        *sh.slots[i].lock().unwrap_or_else(|p| p.into_inner()) = Some(result);
        *sh.reports[i].lock().unwrap_or_else(|p| p.into_inner()) = Some(report);
        for &d in &sh.dependents[i] {
            if sh.pending[d].fetch_sub(1, Ordering::AcqRel) == 1 {
                scope.spawn(move |s| self.run_node(s, sh, d));
            }
        }
    }

    /// Gathers inputs, consults the caches, runs the node and checks its outputs.
    fn evaluate(
        &self,
        sh: &Shared,
        i: usize,
        report: &mut NodeReport,
    ) -> Result<Arc<BTreeMap<String, Value>>, String> {
        let node = &sh.graph.nodes[i];
        let decl = &node.decl;
        // Upstream failures block this node.
        for &d in &node.deps {
            if let Some(Err(failed)) = sh.slots[d]
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .as_ref()
            {
                report.status = NodeStatus::Blocked { by: failed.clone() };
                return Err(failed.clone());
            }
        }
        let key = sh.keys[i];
        let wanted = sh.wanted[i].as_ref();
        // A cached entry that skipped an output wanted now is kept, to merge with the rerun.
        let mut older = None;
        if !decl.stateful && !sh.fresh[i] {
            if let Some(e) = self.lookup(&key) {
                if e.serves(wanted) {
                    report.status = NodeStatus::Cached;
                    report.written = e.written.clone();
                    return Ok(e.outputs);
                }
                older = Some(e);
            }
        }
        let fail = |report: &mut NodeReport, e: NodeError| {
            report.status = NodeStatus::Failed(e);
            Err(node.id.clone())
        };
        // Inputs.
        let mut inputs = BTreeMap::new();
        for (name, src) in &node.inputs {
            let Some(sdecl) = decl.input(name) else {
                continue;
            };
            let v = match src {
                InputSource::Literal(v) | InputSource::Default(v) => v.clone(),
                InputSource::Unset => continue,
                InputSource::Links(links) => {
                    let mut vals = Vec::new();
                    for (j, out) in links {
                        let slot = sh.slots[*j].lock().unwrap_or_else(|p| p.into_inner());
                        let v = slot
                            .as_ref()
                            .and_then(|r| r.as_ref().ok())
                            .and_then(|o| o.get(out))
                            .cloned();
                        match v {
                            Some(v) => vals.push(v),
                            None => {
                                let e = NodeError::new(
                                    ErrorKind::Internal,
                                    format!(
                                        "'{}' produced no output '{out}'",
                                        sh.graph.nodes[*j].id
                                    ),
                                )
                                .at(name);
                                return fail(report, e);
                            }
                        }
                    }
                    if let SocketType::List(_) = sdecl.ty {
                        let mut flat = Vec::new();
                        for v in vals {
                            match v {
                                Value::List(items) => flat.extend(items.iter().cloned()),
                                other => flat.push(other),
                            }
                        }
                        Value::List(Arc::new(flat))
                    } else {
                        vals.pop().unwrap_or(Value::Bool(false))
                    }
                }
            };
            match v.convert_to(&sdecl.ty) {
                Some(v) => {
                    inputs.insert(name.clone(), v);
                }
                None => {
                    let e = NodeError::invalid(
                        name,
                        format!("cannot convert {} to {}", v.socket_type(), sdecl.ty),
                    );
                    return fail(report, e);
                }
            }
        }
        // State (taken out while the node runs, put back after).
        let mut state = if decl.stateful {
            self.states
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .remove(&node.id)
        } else {
            None
        };
        let Some(exec) = decl.exec.clone() else {
            return fail(
                report,
                NodeError::new(ErrorKind::Internal, "node has no implementation"),
            );
        };
        let mut ctx = ExecContext {
            node_id: &node.id,
            decl,
            inputs,
            outputs: BTreeMap::new(),
            frame: sh.frame,
            state: &mut state,
            files: &sh.opts.files,
            logs: Vec::new(),
            written: Vec::new(),
            progress: sh.opts.progress.clone(),
            wanted: wanted.cloned(),
        };
        let res = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| exec(&mut ctx)));
        let outputs = std::mem::take(&mut ctx.outputs);
        report.logs = std::mem::take(&mut ctx.logs);
        report.written = std::mem::take(&mut ctx.written);
        drop(ctx);
        if decl.stateful {
            if let Some(s) = state {
                self.states
                    .lock()
                    .unwrap_or_else(|p| p.into_inner())
                    .insert(node.id.clone(), s);
            }
        }
        match res {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return fail(report, e),
            Err(panic) => {
                let msg = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                return fail(
                    report,
                    NodeError::new(ErrorKind::Internal, format!("the node panicked: {msg}")),
                );
            }
        }
        let is_wanted = |name: &str| wanted.is_none_or(|w| w.contains(name));
        let mut skipped = Vec::new();
        for o in &decl.outputs {
            match outputs.get(&o.name) {
                None if !is_wanted(&o.name) => skipped.push(o.name.clone()),
                None if o.optional => {}
                None => {
                    return fail(
                        report,
                        NodeError::new(
                            ErrorKind::Internal,
                            format!("produced no output '{}'", o.name),
                        ),
                    )
                }
                Some(v)
                    if !o.ty.accepts(&v.socket_type())
                        && !matches!(v, Value::List(l) if l.is_empty()) =>
                {
                    let e = NodeError::new(
                        ErrorKind::Internal,
                        format!(
                            "output '{}' should be {} but is {}",
                            o.name,
                            o.ty,
                            v.socket_type()
                        ),
                    );
                    return fail(report, e);
                }
                _ => {}
            }
        }
        let mut e = Entry {
            outputs: Arc::new(outputs),
            written: report.written.clone(),
            skipped,
        };
        if let Some(older) = &older {
            e = e.merged_with(older);
        }
        let outputs = e.outputs.clone();
        if !decl.stateful {
            if let Some(d) = &self.disk {
                d.put(&key, &e);
            }
            self.memory
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .put(key, e);
        }
        Ok(outputs)
    }

    fn lookup(&self, key: &Key) -> Option<Entry> {
        let hit = self
            .memory
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .get(key);
        let hit = hit.or_else(|| {
            let e = self.disk.as_ref()?.get(key)?;
            self.memory
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .put(*key, e.clone());
            Some(e)
        });
        hit.filter(|e| e.files_present())
    }
}

struct Shared<'a> {
    graph: &'a ValidGraph,
    opts: &'a RunOptions,
    frame: i64,
    keys: &'a [Key],
    fresh: &'a [bool],
    wanted: &'a [Option<BTreeSet<String>>],
    slots: &'a [Slot],
    reports: &'a [Mutex<Option<NodeReport>>],
    dependents: &'a [Vec<usize>],
    pending: &'a [AtomicUsize],
}

/// Computes every needed node's cache key in topological order.
pub fn cache_keys(graph: &ValidGraph, need: &[bool], files: &FileEnv, frame: i64) -> Vec<Key> {
    let mut keys = vec![[0u8; 32]; graph.nodes.len()];
    for (i, node) in graph.nodes.iter().enumerate() {
        if !need[i] {
            continue;
        }
        let d = &node.decl;
        let mut h = blake3::Hasher::new();
        h.update(b"cgnodes-key-1\0");
        h.update(d.type_name.as_bytes());
        h.update(b"\0");
        h.update(d.source.as_bytes());
        h.update(b"\0");
        for (name, src) in &node.inputs {
            h.update(name.as_bytes());
            h.update(b"=");
            match src {
                InputSource::Literal(v) | InputSource::Default(v) => {
                    let j = v.to_json().map(|j| j.to_string()).unwrap_or_default();
                    h.update(j.as_bytes());
                    let role = d.input(name).map(|s| s.file).unwrap_or_default();
                    if let (FileRole::Input, Value::String(p)) = (role, v) {
                        let path = files.input_path(p);
                        h.update(path.to_string_lossy().as_bytes());
                        if let Ok(m) = std::fs::metadata(&path) {
                            h.update(&m.len().to_le_bytes());
                            if let Ok(t) = m.modified().and_then(|t| {
                                t.duration_since(std::time::UNIX_EPOCH)
                                    .map_err(std::io::Error::other)
                            }) {
                                h.update(&t.as_nanos().to_le_bytes());
                            }
                        }
                    }
                }
                InputSource::Links(ls) => {
                    for (j, out) in ls {
                        h.update(&keys[*j]);
                        h.update(out.as_bytes());
                        h.update(b";");
                    }
                }
                InputSource::Unset => {
                    h.update(b"<unset>");
                }
            }
            h.update(b"\0");
        }
        if d.time_dependent || d.stateful {
            h.update(b"frame");
            h.update(&frame.to_le_bytes());
        }
        if d.sink || d.inputs.iter().any(|s| s.file == FileRole::Output) {
            h.update(files.out_dir.to_string_lossy().as_bytes());
            h.update(&[u8::from(files.allow_write_anywhere)]);
        }
        keys[i] = *h.finalize().as_bytes();
    }
    keys
}

/// Reads a memory figure (in KiB) from /proc/self/status; 0 where unavailable.
fn read_status_kib(field: &str) -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(field))
                .and_then(|l| l.split_whitespace().nth(1).and_then(|x| x.parse().ok()))
        })
        .unwrap_or(0)
}
