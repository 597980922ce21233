//! The scheduler: runs the nodes that the requested outputs need, in parallel where branches
//! are independent, serving unchanged nodes from the caches and keeping simulation state
//! between frames.

mod evaluate;
mod plan;
mod report;

pub use plan::{cache_keys, input_files};
pub use report::{NodeReport, NodeStatus, RunReport};

use crate::cache::{DiskCache, Evicted, Key, MemoryCache};
use crate::validate::ValidGraph;
use cgnodes_api::node::{FileEnv, LogFn, ProgressFn};
use cgnodes_api::types::Value;
use report::read_status_kib;
use std::any::Any;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
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
    /// Receives node log lines as they are written (the run report keeps them too).
    pub log: Option<LogFn>,
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
    /// The most bytes one buffer request of a node may take (`--max-memory`); `None` uses
    /// `node::default_memory_limit()` (CGNODES_MAX_MEMORY, else half the physical memory).
    pub max_memory: Option<u64>,
}

impl RunOptions {
    /// The memory limit nodes check their buffers against (`ExecContext::reserve_bytes`).
    pub fn memory_limit(&self) -> u64 {
        self.max_memory
            .unwrap_or_else(cgnodes_api::node::default_memory_limit)
    }
}

/// Runs graphs. Holds the caches, the simulation state of stateful nodes (by node id) and the
/// thread pool, so repeated runs (frames, sweeps) reuse what did not change.
pub struct Executor {
    pool: rayon::ThreadPool,
    memory: Mutex<MemoryCache>,
    disk: Option<DiskCache>,
    states: Mutex<HashMap<String, Box<dyn Any + Send>>>,
    /// For each stateful node that holds state: its key at the frame that last advanced it
    /// (the history its next key chains onto; see `crate::cache`).
    histories: Mutex<HashMap<String, Key>>,
    /// Stateful nodes that failed or were blocked, by node id, with the frame: they stay
    /// stopped (issue 23: a simulation must not restart from its initial state mid-range).
    stopped: Mutex<HashMap<String, i64>>,
}

/// The node whose failure stopped a node: itself, or the upstream node that blocked it.
#[derive(Clone, Debug)]
struct Failed(String);

type Slot = Mutex<Option<Result<Arc<BTreeMap<String, Value>>, Failed>>>;

/// Why an executor could not start.
#[derive(Debug, thiserror::Error)]
pub enum StartError {
    /// The thread pool could not be built.
    #[error("cannot start threads: {0}")]
    Threads(#[from] rayon::ThreadPoolBuildError),
    /// The disk cache folder could not be opened.
    #[error("cache folder {}: {source}", dir.display())]
    Cache {
        dir: std::path::PathBuf,
        source: std::io::Error,
    },
}

impl Executor {
    /// An executor with `threads` worker threads (all cores when `None`) and an optional
    /// disk cache.
    pub fn new(
        threads: Option<usize>,
        cache_dir: Option<&std::path::Path>,
    ) -> Result<Executor, StartError> {
        let mut b = rayon::ThreadPoolBuilder::new();
        if let Some(n) = threads {
            b = b.num_threads(n.max(1));
        }
        let pool = b.build()?;
        let disk = match cache_dir {
            Some(d) => Some(DiskCache::open(d).map_err(|source| StartError::Cache {
                dir: d.to_path_buf(),
                source,
            })?),
            None => None,
        };
        Ok(Executor {
            pool,
            memory: Mutex::new(MemoryCache::default()),
            disk,
            states: Mutex::new(HashMap::new()),
            histories: Mutex::new(HashMap::new()),
            stopped: Mutex::new(HashMap::new()),
        })
    }

    /// Drops the state of every stateful node (simulations restart), including the stopped
    /// mark of those that failed.
    pub fn reset_states(&self) {
        self.states
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clear();
        self.histories
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clear();
        self.stopped
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clear();
    }

    /// Trims the disk cache to `limit` bytes, removing the least recently used entries
    /// (`limit` 0: no limit); `None` without a disk cache.
    pub fn evict_disk_cache(&self, limit: u64) -> Option<Evicted> {
        self.disk.as_ref().map(|d| d.evict(limit))
    }

    /// The frame at which stateful node `id` failed or was blocked, if it did: from then on
    /// it reports `NodeStatus::Stopped` and the nodes it feeds are blocked.
    pub fn stopped_since(&self, id: &str) -> Option<i64> {
        self.stopped
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .get(id)
            .copied()
    }

    /// Marks a stateful node whose step did not happen at `frame` as stopped, and drops its
    /// state: a later frame would continue from a history with a step missing.
    fn stop(&self, id: &str, frame: i64) {
        self.stopped
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .entry(id.to_string())
            .or_insert(frame);
        self.states
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .remove(id);
        self.histories
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .remove(id);
    }

    /// Runs `graph` for one frame.
    pub fn run(&self, graph: &ValidGraph, opts: &RunOptions, frame: i64) -> RunReport {
        let start = Instant::now();
        self.memory
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .next_generation();
        let n = graph.nodes.len();
        let (need, wanted) = plan::wanted_outputs(graph, opts);
        let keys = {
            // Only a node that still holds its state continues its history.
            let states = self.states.lock().unwrap_or_else(|p| p.into_inner());
            let mut history = self.histories.lock().unwrap_or_else(|p| p.into_inner());
            history.retain(|id, _| states.contains_key(id));
            plan::cache_keys(graph, &need, &opts.files, frame, &history)
        };
        let final_keys: Vec<OnceLock<Key>> = (0..n).map(|_| OnceLock::new()).collect();
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
            final_keys: &final_keys,
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
                written_values: Vec::new(),
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
            written_values: Vec::new(),
        };
        let result = match self.stopped_since(&node.id) {
            Some(since) if node.decl.stateful => {
                report.status = NodeStatus::Stopped { since };
                Err(Failed(node.id.clone()))
            }
            _ => self.evaluate(sh, i, &mut report),
        };
        if node.decl.stateful && result.is_err() {
            self.stop(&node.id, sh.frame);
        }
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
}

struct Shared<'a> {
    graph: &'a ValidGraph,
    opts: &'a RunOptions,
    frame: i64,
    keys: &'a [Key],
    /// Keys completed at evaluation time (stamps of linked file paths), set by each node
    /// before its dependents start.
    final_keys: &'a [OnceLock<Key>],
    fresh: &'a [bool],
    wanted: &'a [Option<BTreeSet<String>>],
    slots: &'a [Slot],
    reports: &'a [Mutex<Option<NodeReport>>],
    dependents: &'a [Vec<usize>],
    pending: &'a [AtomicUsize],
}
