//! Validation: checks a graph against the registry before anything runs, reporting every
//! error together, each naming the file, node id, node type and socket.

use crate::graph::format::{split_link, Graph};
use cgnodes_api::node::{FileRole, NodeDecl};
use cgnodes_api::registry::{closest, Registry};
use cgnodes_api::types::{SocketType, Value};
use petgraph::graph::{DiGraph, NodeIndex};
use std::collections::HashMap;
use std::fmt;
use std::path::PathBuf;
use std::sync::Arc;

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
    let file = graph.file.clone();
    let spec = &graph.spec;
    let mut errors = Vec::new();
    // Node types.
    let mut decls: HashMap<&str, Arc<NodeDecl>> = HashMap::new();
    for (id, n) in &spec.nodes {
        match registry.get(&n.node_type) {
            Some(d) => {
                decls.insert(id, d.clone());
            }
            None => errors.push(GraphError::UnknownNodeType {
                file: file.clone(),
                node: id.clone(),
                node_type: n.node_type.clone(),
                suggestion: registry.closest(&n.node_type),
            }),
        }
    }
    // Sockets, literals and links.
    let mut edges: Vec<(String, String)> = Vec::new();
    let mut raw_inputs: HashMap<&str, Vec<(String, RawSource)>> = HashMap::new();
    for (id, n) in &spec.nodes {
        let Some(decl) = decls.get(id.as_str()) else {
            continue;
        };
        let ctx = |socket: &str| {
            (
                file.clone(),
                id.clone(),
                n.node_type.clone(),
                socket.to_string(),
            )
        };
        let names = || decl.inputs.iter().map(|s| s.name.as_str());
        for key in n.params.keys().chain(n.inputs.keys()) {
            if decl.input(key).is_none() {
                let (file, node, node_type, socket) = ctx(key);
                errors.push(GraphError::UnknownSocket {
                    file,
                    node,
                    node_type,
                    side: Side::Input,
                    suggestion: closest(key, names()),
                    socket,
                });
            }
        }
        let mut ins = Vec::new();
        for s in &decl.inputs {
            let (file, node, node_type, socket) = ctx(&s.name);
            let lit = n.params.get(&s.name);
            let link = n.inputs.get(&s.name);
            let src = match (lit, link) {
                (Some(_), Some(_)) => {
                    errors.push(GraphError::LiteralAndLink {
                        file,
                        node,
                        node_type,
                        socket,
                    });
                    continue;
                }
                (Some(j), None) => {
                    match Value::from_json(&s.ty, j).and_then(|v| s.check_literal(&v).map(|()| v)) {
                        Err(message) => {
                            errors.push(GraphError::BadParam {
                                file,
                                node,
                                node_type,
                                socket,
                                message,
                            });
                            continue;
                        }
                        Ok(v) => {
                            if s.file == FileRole::Input {
                                if let Value::String(p) = &v {
                                    let path = cgnodes_api::node::FileEnv {
                                        graph_dir: graph.dir.clone(),
                                        asset_dirs: asset_dirs.to_vec(),
                                        ..Default::default()
                                    }
                                    .input_path(p);
                                    if !p.contains('{') && !path.exists() {
                                        errors.push(GraphError::MissingFile {
                                            file,
                                            node,
                                            node_type,
                                            socket,
                                            path: path.display().to_string(),
                                        });
                                        continue;
                                    }
                                }
                            }
                            RawSource::Literal(v)
                        }
                    }
                }
                (None, Some(l)) => {
                    let links = l.links();
                    if links.len() != 1 && !matches!(s.ty, SocketType::List(_)) {
                        errors.push(GraphError::TooManyLinks {
                            file,
                            node,
                            node_type,
                            socket,
                            count: links.len(),
                        });
                        continue;
                    }
                    let mut parsed = Vec::new();
                    for link in links {
                        let dangling = |reason: String| GraphError::DanglingLink {
                            file: file.clone(),
                            node: node.clone(),
                            node_type: node_type.clone(),
                            socket: socket.clone(),
                            link: link.to_string(),
                            reason,
                        };
                        let Some((from, out)) = split_link(link) else {
                            errors.push(dangling(
                                "which is not of the form \"<node id>.<output socket>\"".into(),
                            ));
                            continue;
                        };
                        let Some(up) = spec.nodes.get(from) else {
                            errors.push(dangling(format!(
                                "but there is no node '{from}'{}",
                                hint(&closest(from, spec.nodes.keys().map(String::as_str)))
                            )));
                            continue;
                        };
                        edges.push((from.to_string(), id.clone()));
                        let Some(up_decl) = decls.get(from) else {
                            continue;
                        };
                        let Some(out_decl) = up_decl.output(out) else {
                            errors.push(GraphError::UnknownSocket {
                                file: file.clone(),
                                node: from.to_string(),
                                node_type: up.node_type.clone(),
                                side: Side::Output,
                                socket: out.to_string(),
                                suggestion: closest(
                                    out,
                                    up_decl.outputs.iter().map(|s| s.name.as_str()),
                                ),
                            });
                            continue;
                        };
                        if !s.ty.accepts(&out_decl.ty) {
                            errors.push(GraphError::MismatchedInputSlotType {
                                file: file.clone(),
                                node: node.clone(),
                                node_type: node_type.clone(),
                                socket: socket.clone(),
                                expected: s.ty.clone(),
                                actual: out_decl.ty.clone(),
                                from_node: from.to_string(),
                                from_socket: out.to_string(),
                            });
                            continue;
                        }
                        parsed.push((from.to_string(), out.to_string()));
                    }
                    RawSource::Links(parsed)
                }
                (None, None) => match s.default_value() {
                    Some(v) => RawSource::Default(v),
                    None if s.optional => RawSource::Unset,
                    None => {
                        errors.push(GraphError::MissingInput {
                            file,
                            node,
                            node_type,
                            socket,
                        });
                        continue;
                    }
                },
            };
            ins.push((s.name.clone(), src));
        }
        raw_inputs.insert(id, ins);
    }
    // Targets.
    let mut target_ids: Vec<String> = Vec::new();
    match &spec.outputs {
        Some(outs) => {
            for o in outs {
                if spec.nodes.contains_key(o) {
                    target_ids.push(o.clone());
                } else {
                    errors.push(GraphError::UnknownTarget {
                        file: file.clone(),
                        node: o.clone(),
                        suggestion: closest(o, spec.nodes.keys().map(String::as_str)),
                    });
                }
            }
        }
        None => {
            target_ids.extend(
                spec.nodes
                    .keys()
                    .filter(|id| decls.get(id.as_str()).is_some_and(|d| d.sink))
                    .cloned(),
            );
        }
    }
    // Cycles and order, with petgraph.
    let mut g: DiGraph<&str, ()> = DiGraph::new();
    let mut gi: HashMap<&str, NodeIndex> = HashMap::new();
    for id in spec.nodes.keys() {
        gi.insert(id, g.add_node(id));
    }
    for (a, b) in &edges {
        g.add_edge(gi[a.as_str()], gi[b.as_str()], ());
    }
    let order = match petgraph::algo::toposort(&g, None) {
        Ok(o) => o,
        Err(_) => {
            for scc in petgraph::algo::tarjan_scc(&g) {
                let cyclic = scc.len() > 1 || g.contains_edge(scc[0], scc[0]);
                if cyclic {
                    errors.push(GraphError::Cycle {
                        file: file.clone(),
                        path: cycle_path(&g, &scc),
                    });
                }
            }
            Vec::new()
        }
    };
    if !errors.is_empty() {
        return Err(errors);
    }
    let ids: Vec<&str> = order.iter().map(|&i| g[i]).collect();
    let index: HashMap<String, usize> = ids
        .iter()
        .enumerate()
        .map(|(i, id)| (id.to_string(), i))
        .collect();
    let mut nodes = Vec::with_capacity(ids.len());
    for id in &ids {
        let raw = raw_inputs.remove(id).unwrap_or_default();
        let mut deps = Vec::new();
        let inputs = raw
            .into_iter()
            .map(|(name, r)| {
                let src = match r {
                    RawSource::Literal(v) => InputSource::Literal(v),
                    RawSource::Default(v) => InputSource::Default(v),
                    RawSource::Unset => InputSource::Unset,
                    RawSource::Links(ls) => InputSource::Links(
                        ls.into_iter()
                            .map(|(n, s)| {
                                deps.push(index[&n]);
                                (index[&n], s)
                            })
                            .collect(),
                    ),
                };
                (name, src)
            })
            .collect();
        deps.sort_unstable();
        deps.dedup();
        nodes.push(ValidNode {
            id: id.to_string(),
            decl: decls[id].clone(),
            inputs,
            deps,
        });
    }
    let targets = target_ids.iter().map(|t| index[t]).collect();
    Ok(ValidGraph {
        file,
        dir: graph.dir.clone(),
        nodes,
        index,
        targets,
        hash: graph.hash.clone(),
    })
}

enum RawSource {
    Literal(Value),
    Links(Vec<(String, String)>),
    Default(Value),
    Unset,
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
