//! The checks behind `validate_with`, one per part of the graph: node types, socket names,
//! each input's literal, links or default, the targets, and the order (cycles).

use super::{hint, GraphError, InputSource, Side, ValidGraph, ValidNode};
use crate::graph::format::{split_link, Graph, LinkSpec, NodeSpec};
use cgnodes_api::node::{FileEnv, FileRole, NodeDecl, SocketDecl};
use cgnodes_api::registry::{closest, Registry};
use cgnodes_api::types::{SocketType, Value};
use petgraph::graph::{DiGraph, NodeIndex};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

/// Where an input's value comes from, with links still by node id.
pub(super) enum RawSource {
    Literal(Value),
    Links(Vec<(String, String)>),
    Default(Value),
    Unset,
}

/// The input socket an error is about: (file, node, node type, socket).
struct At {
    file: PathBuf,
    node: String,
    node_type: String,
    socket: String,
}

/// A graph being checked, collecting every error.
pub(super) struct Checker<'a> {
    graph: &'a Graph,
    asset_dirs: &'a [PathBuf],
    decls: HashMap<&'a str, Arc<NodeDecl>>,
    /// Links as (from node, to node).
    edges: Vec<(String, String)>,
    pub(super) errors: Vec<GraphError>,
}

impl<'a> Checker<'a> {
    /// Looks every node's type up in `registry`.
    pub(super) fn new(graph: &'a Graph, registry: &Registry, asset_dirs: &'a [PathBuf]) -> Self {
        let mut errors = Vec::new();
        let mut decls = HashMap::new();
        for (id, n) in &graph.spec.nodes {
            match registry.get(&n.node_type) {
                Some(d) => {
                    decls.insert(id.as_str(), d.clone());
                }
                None => errors.push(GraphError::UnknownNodeType {
                    file: graph.file.clone(),
                    node: id.clone(),
                    node_type: n.node_type.clone(),
                    suggestion: registry.closest(&n.node_type),
                }),
            }
        }
        Checker {
            graph,
            asset_dirs,
            decls,
            edges: Vec::new(),
            errors,
        }
    }

    /// Every known node's inputs with their sources, by node id.
    pub(super) fn inputs(&mut self) -> HashMap<&'a str, Vec<(String, RawSource)>> {
        let mut raw_inputs = HashMap::new();
        for (id, n) in &self.graph.spec.nodes {
            let Some(decl) = self.decls.get(id.as_str()).cloned() else {
                continue;
            };
            self.check_socket_names(id, n, &decl);
            let ins = decl
                .inputs
                .iter()
                .filter_map(|s| Some((s.name.clone(), self.input(id, n, s)?)))
                .collect();
            raw_inputs.insert(id.as_str(), ins);
        }
        raw_inputs
    }

    /// Every parameter and link names an input socket of the node.
    fn check_socket_names(&mut self, id: &str, n: &NodeSpec, decl: &NodeDecl) {
        for key in n.params.keys().chain(n.inputs.keys()) {
            if decl.input(key).is_none() {
                self.errors.push(GraphError::UnknownSocket {
                    file: self.graph.file.clone(),
                    node: id.to_string(),
                    node_type: n.node_type.clone(),
                    side: Side::Input,
                    socket: key.clone(),
                    suggestion: closest(key, decl.inputs.iter().map(|s| s.name.as_str())),
                });
            }
        }
    }

    /// Where input `s` of node `id` gets its value; `None` after recording an error.
    fn input(&mut self, id: &str, n: &NodeSpec, s: &SocketDecl) -> Option<RawSource> {
        let at = At {
            file: self.graph.file.clone(),
            node: id.to_string(),
            node_type: n.node_type.clone(),
            socket: s.name.clone(),
        };
        let found = match (n.params.get(&s.name), n.inputs.get(&s.name)) {
            (Some(_), Some(_)) => Err(GraphError::LiteralAndLink {
                file: at.file,
                node: at.node,
                node_type: at.node_type,
                socket: at.socket,
            }),
            (Some(j), None) => self.literal(at, s, j),
            (None, Some(l)) => return self.links(at, s, l),
            (None, None) => match s.default_value() {
                Some(v) => Ok(RawSource::Default(v)),
                None if s.optional => Ok(RawSource::Unset),
                None => Err(GraphError::MissingInput {
                    file: at.file,
                    node: at.node,
                    node_type: at.node_type,
                    socket: at.socket,
                }),
            },
        };
        found.map_err(|e| self.errors.push(e)).ok()
    }

    /// A literal parameter: of the socket's type, in its range, and an input file that exists
    /// (unless its name holds a `{frame}` pattern).
    // Each error goes straight into the checker's list of GraphErrors; boxing it for the
    // return would only be undone there.
    #[allow(clippy::result_large_err)]
    fn literal(
        &self,
        at: At,
        s: &SocketDecl,
        j: &serde_json::Value,
    ) -> Result<RawSource, GraphError> {
        let v = match Value::from_json(&s.ty, j).and_then(|v| s.check_literal(&v).map(|()| v)) {
            Ok(v) => v,
            Err(message) => {
                return Err(GraphError::BadParam {
                    file: at.file,
                    node: at.node,
                    node_type: at.node_type,
                    socket: at.socket,
                    message,
                })
            }
        };
        if let (FileRole::Input, Value::String(p)) = (s.file, &v) {
            let path = FileEnv {
                graph_dir: self.graph.dir.clone(),
                asset_dirs: self.asset_dirs.to_vec(),
                ..Default::default()
            }
            .input_path(p);
            if !p.contains('{') && !path.exists() {
                return Err(GraphError::MissingFile {
                    file: at.file,
                    node: at.node,
                    node_type: at.node_type,
                    socket: at.socket,
                    path: path.display().to_string(),
                });
            }
        }
        Ok(RawSource::Literal(v))
    }

    /// The links into input `s`: one unless it takes a list, each to a known output of a
    /// type the input accepts.
    fn links(&mut self, at: At, s: &SocketDecl, l: &LinkSpec) -> Option<RawSource> {
        let links = l.links();
        if links.len() != 1 && !matches!(s.ty, SocketType::List(_)) {
            self.errors.push(GraphError::TooManyLinks {
                file: at.file,
                node: at.node,
                node_type: at.node_type,
                socket: at.socket,
                count: links.len(),
            });
            return None;
        }
        let mut parsed = Vec::new();
        for link in links {
            match self.link(&at, s, link) {
                Ok(Some(p)) => parsed.push(p),
                Ok(None) => {}
                Err(e) => self.errors.push(e),
            }
        }
        Some(RawSource::Links(parsed))
    }

    /// One link `node.output` into input `s`, recorded as an edge once its node exists;
    /// `None` when the upstream node's type is unknown (already an error).
    // As `literal`: the error goes straight into the checker's list.
    #[allow(clippy::result_large_err)]
    fn link(
        &mut self,
        at: &At,
        s: &SocketDecl,
        link: &str,
    ) -> Result<Option<(String, String)>, GraphError> {
        let spec = &self.graph.spec;
        let dangling = |reason: String| GraphError::DanglingLink {
            file: at.file.clone(),
            node: at.node.clone(),
            node_type: at.node_type.clone(),
            socket: at.socket.clone(),
            link: link.to_string(),
            reason,
        };
        let Some((from, out)) = split_link(link) else {
            return Err(dangling(
                "which is not of the form \"<node id>.<output socket>\"".into(),
            ));
        };
        let Some(up) = spec.nodes.get(from) else {
            return Err(dangling(format!(
                "but there is no node '{from}'{}",
                hint(&closest(from, spec.nodes.keys().map(String::as_str)))
            )));
        };
        self.edges.push((from.to_string(), at.node.clone()));
        let Some(up_decl) = self.decls.get(from) else {
            return Ok(None);
        };
        let Some(out_decl) = up_decl.output(out) else {
            return Err(GraphError::UnknownSocket {
                file: at.file.clone(),
                node: from.to_string(),
                node_type: up.node_type.clone(),
                side: Side::Output,
                socket: out.to_string(),
                suggestion: closest(out, up_decl.outputs.iter().map(|s| s.name.as_str())),
            });
        };
        if !s.ty.accepts(&out_decl.ty) {
            return Err(GraphError::MismatchedInputSlotType {
                file: at.file.clone(),
                node: at.node.clone(),
                node_type: at.node_type.clone(),
                socket: at.socket.clone(),
                expected: s.ty.clone(),
                actual: out_decl.ty.clone(),
                from_node: from.to_string(),
                from_socket: out.to_string(),
            });
        }
        Ok(Some((from.to_string(), out.to_string())))
    }

    /// The nodes the graph asks for: `outputs`, else every sink.
    pub(super) fn targets(&mut self) -> Vec<String> {
        let spec = &self.graph.spec;
        let Some(outs) = &spec.outputs else {
            return spec
                .nodes
                .keys()
                .filter(|id| self.decls.get(id.as_str()).is_some_and(|d| d.sink))
                .cloned()
                .collect();
        };
        let mut target_ids = Vec::new();
        for o in outs {
            if spec.nodes.contains_key(o) {
                target_ids.push(o.clone());
            } else {
                self.errors.push(GraphError::UnknownTarget {
                    file: self.graph.file.clone(),
                    node: o.clone(),
                    suggestion: closest(o, spec.nodes.keys().map(String::as_str)),
                });
            }
        }
        target_ids
    }

    /// Node ids in topological order (with petgraph); empty after recording each cycle.
    pub(super) fn order(&mut self) -> Vec<&'a str> {
        let spec = &self.graph.spec;
        let mut g: DiGraph<&str, ()> = DiGraph::new();
        let mut gi: HashMap<&str, NodeIndex> = HashMap::new();
        for id in spec.nodes.keys() {
            gi.insert(id, g.add_node(id));
        }
        for (a, b) in &self.edges {
            g.add_edge(gi[a.as_str()], gi[b.as_str()], ());
        }
        match petgraph::algo::toposort(&g, None) {
            Ok(o) => o.iter().map(|&i| g[i]).collect(),
            Err(_) => {
                for scc in petgraph::algo::tarjan_scc(&g) {
                    if scc.len() > 1 || g.contains_edge(scc[0], scc[0]) {
                        self.errors.push(GraphError::Cycle {
                            file: self.graph.file.clone(),
                            path: super::cycle_path(&g, &scc),
                        });
                    }
                }
                Vec::new()
            }
        }
    }

    /// The valid graph: nodes in `ids` order, links by node index.
    pub(super) fn finish(
        self,
        ids: &[&'a str],
        mut raw_inputs: HashMap<&'a str, Vec<(String, RawSource)>>,
        target_ids: &[String],
    ) -> ValidGraph {
        let index: HashMap<String, usize> = ids
            .iter()
            .enumerate()
            .map(|(i, id)| (id.to_string(), i))
            .collect();
        let nodes = ids
            .iter()
            .map(|id| {
                let raw = raw_inputs.remove(id).unwrap_or_default();
                valid_node(id, self.decls[id].clone(), raw, &index)
            })
            .collect();
        let targets = target_ids.iter().map(|t| index[t]).collect();
        ValidGraph {
            file: self.graph.file.clone(),
            dir: self.graph.dir.clone(),
            nodes,
            index,
            targets,
            hash: self.graph.hash.clone(),
        }
    }
}

/// Node `id` with its links resolved to node indices through `index`.
fn valid_node(
    id: &str,
    decl: Arc<NodeDecl>,
    raw: Vec<(String, RawSource)>,
    index: &HashMap<String, usize>,
) -> ValidNode {
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
    ValidNode {
        id: id.to_string(),
        decl,
        inputs,
        deps,
    }
}
