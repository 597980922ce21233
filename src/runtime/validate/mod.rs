//! Validation: checks a graph against the registry before anything runs, reporting every
//! error together, each naming the file, node id, node type and socket.

use crate::graph::format::Graph;
use cgnodes_api::node::NodeDecl;
use cgnodes_api::registry::Registry;
use cgnodes_api::types::{SocketType, Value};
use petgraph::graph::{DiGraph, NodeIndex};
use std::collections::HashMap;
use std::fmt;
use std::path::PathBuf;
use std::sync::Arc;

mod check;
mod partial;
pub use partial::validate_needed;

/// Which side of a node a socket is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Input,
    Output,
}

impl fmt::Display for Side {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Side::Input => "input",
            Side::Output => "output",
        })
    }
}

fn hint(s: &Option<String>) -> String {
    s.as_ref()
        .map(|s| format!(" (did you mean '{s}'?)"))
        .unwrap_or_default()
}

/// A problem with a graph, found before it runs.
#[derive(Clone, Debug, thiserror::Error)]
pub enum GraphError {
    #[error(
        "{file}: node '{node}': unknown node type '{node_type}'{}",
        hint(suggestion)
    )]
    UnknownNodeType {
        file: PathBuf,
        node: String,
        node_type: String,
        suggestion: Option<String>,
    },
    #[error(
        "{file}: node '{node}' ({node_type}): no {side} socket '{socket}'{}",
        hint(suggestion)
    )]
    UnknownSocket {
        file: PathBuf,
        node: String,
        node_type: String,
        side: Side,
        socket: String,
        suggestion: Option<String>,
    },
    #[error("{file}: node '{node}' ({node_type}): input '{socket}' is required but has no value or link")]
    MissingInput {
        file: PathBuf,
        node: String,
        node_type: String,
        socket: String,
    },
    #[error("{file}: node '{node}' ({node_type}): input '{socket}' expects {expected} but '{from_node}.{from_socket}' gives {actual}")]
    MismatchedInputSlotType {
        file: PathBuf,
        node: String,
        node_type: String,
        socket: String,
        expected: SocketType,
        actual: SocketType,
        from_node: String,
        from_socket: String,
    },
    #[error("{file}: node '{node}' ({node_type}): input '{socket}': {message}")]
    BadParam {
        file: PathBuf,
        node: String,
        node_type: String,
        socket: String,
        message: String,
    },
    #[error("{file}: node '{node}' ({node_type}): input '{socket}' has both a literal in params and a link in inputs; give one")]
    LiteralAndLink {
        file: PathBuf,
        node: String,
        node_type: String,
        socket: String,
    },
    #[error("{file}: node '{node}' ({node_type}): input '{socket}' links to '{link}', {reason}")]
    DanglingLink {
        file: PathBuf,
        node: String,
        node_type: String,
        socket: String,
        link: String,
        reason: String,
    },
    #[error("{file}: node '{node}' ({node_type}): input '{socket}' takes one link, got {count}")]
    TooManyLinks {
        file: PathBuf,
        node: String,
        node_type: String,
        socket: String,
        count: usize,
    },
    #[error("{file}: cycle: {}", path.join(" -> "))]
    Cycle { file: PathBuf, path: Vec<String> },
    #[error(
        "{file}: \"outputs\" names '{node}', which is not a node of the graph{}",
        hint(suggestion)
    )]
    UnknownTarget {
        file: PathBuf,
        node: String,
        suggestion: Option<String>,
    },
    #[error("{file}: node '{node}' ({node_type}): input '{socket}': file '{path}' does not exist")]
    MissingFile {
        file: PathBuf,
        node: String,
        node_type: String,
        socket: String,
        path: String,
    },
}

impl GraphError {
    /// The node the error is about, if any.
    pub fn node(&self) -> Option<&str> {
        use GraphError::*;
        match self {
            UnknownNodeType { node, .. }
            | UnknownSocket { node, .. }
            | MissingInput { node, .. }
            | MismatchedInputSlotType { node, .. }
            | BadParam { node, .. }
            | LiteralAndLink { node, .. }
            | DanglingLink { node, .. }
            | TooManyLinks { node, .. }
            | UnknownTarget { node, .. }
            | MissingFile { node, .. } => Some(node),
            Cycle { .. } => None,
        }
    }
}

/// Where an input's value comes from.
#[derive(Clone, Debug)]
pub enum InputSource {
    /// A literal from `params` (already converted to the socket's type).
    Literal(Value),
    /// Links from other nodes' outputs: (node index, output socket).
    Links(Vec<(usize, String)>),
    /// The socket's default.
    Default(Value),
    /// Nothing: an optional input left open.
    Unset,
}

/// A node that passed validation.
#[derive(Clone, Debug)]
pub struct ValidNode {
    /// Node id.
    pub id: String,
    /// Its declaration.
    pub decl: Arc<NodeDecl>,
    /// Every input socket with its source, in declaration order.
    pub inputs: Vec<(String, InputSource)>,
    /// Indices of the nodes it reads from.
    pub deps: Vec<usize>,
}

/// A validated graph, ready to plan and run.
#[derive(Clone, Debug)]
pub struct ValidGraph {
    /// The graph file.
    pub file: PathBuf,
    /// Folder relative input paths resolve against.
    pub dir: PathBuf,
    /// Nodes, sorted topologically (every node after the nodes it reads from).
    pub nodes: Vec<ValidNode>,
    /// Node index by id.
    pub index: HashMap<String, usize>,
    /// The nodes the graph asks for (`outputs`, or every sink).
    pub targets: Vec<usize>,
    /// The graph's hash (`Graph::hash`), recorded in every file the run writes.
    pub hash: String,
}

/// Validates `graph` against `registry`, applying `--set` overrides (node, socket, JSON value)
/// first. Returns every error found.
pub fn validate(graph: &Graph, registry: &Registry) -> Result<ValidGraph, Vec<GraphError>> {
    validate_with(graph, registry, &[])
}

/// Like `validate`, also looking for input files in `asset_dirs` (`--assets`).
pub fn validate_with(
    graph: &Graph,
    registry: &Registry,
    asset_dirs: &[std::path::PathBuf],
) -> Result<ValidGraph, Vec<GraphError>> {
    let mut c = check::Checker::new(graph, registry, asset_dirs);
    let raw_inputs = c.inputs();
    let target_ids = c.targets();
    let ids = c.order();
    if !c.errors.is_empty() {
        return Err(c.errors);
    }
    Ok(c.finish(&ids, raw_inputs, &target_ids))
}

/// An ordered cycle through the nodes of a strongly connected component.
fn cycle_path(g: &DiGraph<&str, ()>, scc: &[NodeIndex]) -> Vec<String> {
    let start = *scc.iter().min_by_key(|&&i| g[i]).unwrap_or(&scc[0]);
    let inside: std::collections::HashSet<NodeIndex> = scc.iter().copied().collect();
    // Breadth-first search from `start` back to itself within the component.
    let mut prev: HashMap<NodeIndex, NodeIndex> = HashMap::new();
    let mut queue = std::collections::VecDeque::from([start]);
    while let Some(u) = queue.pop_front() {
        let mut nexts: Vec<NodeIndex> = g.neighbors(u).filter(|v| inside.contains(v)).collect();
        nexts.sort_by_key(|&v| g[v]);
        for v in nexts {
            if v == start {
                let mut path = vec![g[start].to_string()];
                let mut cur = u;
                let mut back = vec![];
                while cur != start {
                    back.push(g[cur].to_string());
                    cur = prev[&cur];
                }
                back.reverse();
                path.extend(back);
                path.push(g[start].to_string());
                return path;
            }
            if let std::collections::hash_map::Entry::Vacant(e) = prev.entry(v) {
                e.insert(u);
                queue.push_back(v);
            }
        }
    }
    scc.iter().map(|&i| g[i].to_string()).collect()
}

impl ValidGraph {
    /// Which nodes the given targets need (themselves and everything upstream).
    pub fn needed(&self, targets: &[usize]) -> Vec<bool> {
        let mut need = vec![false; self.nodes.len()];
        let mut stack: Vec<usize> = targets.to_vec();
        while let Some(i) = stack.pop() {
            if !need[i] {
                need[i] = true;
                stack.extend(&self.nodes[i].deps);
            }
        }
        need
    }

    /// Graphviz text of the graph.
    pub fn to_dot(&self) -> String {
        let mut s = String::from(
            "digraph cgnodes {\n  rankdir=LR;\n  node [shape=record, fontname=\"sans-serif\"];\n",
        );
        for n in &self.nodes {
            s.push_str(&format!(
                "  \"{}\" [label=\"{}\\n({})\"];\n",
                n.id, n.id, n.decl.type_name
            ));
        }
        for n in &self.nodes {
            for (socket, src) in &n.inputs {
                if let InputSource::Links(ls) = src {
                    for (from, out) in ls {
                        s.push_str(&format!(
                            "  \"{}\" -> \"{}\" [label=\"{} -> {}\"];\n",
                            self.nodes[*from].id, n.id, out, socket
                        ));
                    }
                }
            }
        }
        s.push_str("}\n");
        s
    }
}
