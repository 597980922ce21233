//! What a run reports: each node's status, time, memory, log and written files, and the
//! outputs of the nodes that ran or were cached.

use cgnodes_api::node::NodeError;
use cgnodes_api::types::Value;
use std::collections::{BTreeMap, HashMap};
use std::path::PathBuf;
use std::sync::Arc;

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
    /// A stateful node (a simulation) that failed or could not run at an earlier frame of
    /// this executor: it does not run again until `Executor::reset_states`, since restarting
    /// from its initial state would produce frames of another history.
    Stopped {
        /// The frame at which it failed or was blocked.
        since: i64,
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
    /// The values some written files were written from, for the run report (empty when the
    /// node was served from the cache).
    pub written_values: Vec<(PathBuf, Value)>,
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
    /// Whether no node failed (now, or as a simulation stopped at an earlier frame).
    pub fn ok(&self) -> bool {
        !self.nodes.iter().any(|n| {
            matches!(
                n.status,
                NodeStatus::Failed(_) | NodeStatus::Blocked { .. } | NodeStatus::Stopped { .. }
            )
        })
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
    /// Error messages of failed nodes, each naming the file, node id and type. A simulation
    /// stopped at an earlier frame, and the nodes it blocks, were reported in that frame's
    /// report and are not repeated here.
    pub fn errors(&self) -> Vec<String> {
        let stopped = |id: &str| {
            self.node(id)
                .is_some_and(|n| matches!(n.status, NodeStatus::Stopped { .. }))
        };
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
                NodeStatus::Blocked { by } if !stopped(by) => Some(format!(
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

/// Reads a memory figure (in KiB) from /proc/self/status; 0 where unavailable.
pub(super) fn read_status_kib(field: &str) -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(field))
                .and_then(|l| l.split_whitespace().nth(1).and_then(|x| x.parse().ok()))
        })
        .unwrap_or(0)
}
