//! The conversion itself: Framework3D's sockets, nodes and links read into tables, checked
//! against the maps and the registry, then turned into cgnodes nodes and links.

use super::names::{write_usd_path, write_usd_paths};
use super::util::{
    component, f3d_id, feed, helper, literal, short_name, sockets_in_order, value_key,
};
use super::{missing_message, F3dNode, F3dSocket, ImportError, NodeMap};
use crate::graph::format::{GraphFile, LinkSpec, NodeSpec, FORMAT, VERSION};
use cgnodes_api::node::NodeDecl;
use cgnodes_api::registry::Registry;
use serde_json::{Map, Value as J};
use std::collections::{BTreeMap, BTreeSet};

const IMPORTED_FROM: &str = "Framework3D (USTC CG 2024) saved node tree";

/// Converts `raw` with `maps`; with `strict`, fails when a target node is missing from
/// `registry`, else returns the missing ones beside the graph.
pub(super) fn convert(
    raw: &J,
    maps: &BTreeMap<String, NodeMap>,
    registry: &Registry,
    strict: bool,
) -> Result<(GraphFile, Vec<String>), ImportError> {
    let sockets = read_sockets(raw)?;
    let nodes = read_nodes(raw)?;
    check_known(&nodes, maps)?;
    let missing = missing_targets(&nodes, maps, registry)?;
    if !missing.is_empty() && strict {
        return Err(ImportError(missing_message(&missing)));
    }
    let link_ends: BTreeSet<i64> = part(raw, "links_info")?
        .into_iter()
        .flat_map(|o| o.values())
        .filter_map(|l| l.get("EndPinID").and_then(|v| v.as_i64()))
        .collect();
    let usd_paths = write_usd_paths(&nodes, &sockets, &|s| link_ends.contains(&s));
    let mut b = Builder {
        raw,
        maps,
        registry,
        warnings: start_warnings(&nodes, maps),
        sockets,
        nodes: &nodes,
        owner: owners(&nodes),
        link_ends,
        usd_paths,
        out_nodes: BTreeMap::new(),
    };
    for n in &nodes {
        b.add_node(n)?;
    }
    for (lid, from, to) in read_links(raw)? {
        b.add_link(lid, from, to)?;
    }
    for n in &nodes {
        b.add_feeds(n)?;
    }
    Ok((b.finish(), missing))
}

/// Part `k` of the file as an object; Framework3D saves `null` for an empty part (no links,
/// no nodes), read as `None`.
fn part<'a>(raw: &'a J, k: &str) -> Result<Option<&'a Map<String, J>>, ImportError> {
    match raw.get(k) {
        Some(J::Null) => Ok(None),
        v => v
            .and_then(|v| v.as_object())
            .map(Some)
            .ok_or_else(|| ImportError(format!("'{k}' is not an object"))),
    }
}

/// `sockets_info` by socket id.
fn read_sockets(raw: &J) -> Result<BTreeMap<i64, F3dSocket>, ImportError> {
    let mut sockets = BTreeMap::new();
    for (k, s) in part(raw, "sockets_info")?.into_iter().flatten() {
        let id = f3d_id(k, s, "socket")?;
        let text = |f: &str| s.get(f).and_then(|v| v.as_str()).unwrap_or("").to_string();
        sockets.insert(
            id,
            F3dSocket {
                identifier: text("identifier"),
                value: s.get("value").cloned(),
            },
        );
    }
    Ok(sockets)
}

/// `nodes_info`, in id order.
fn read_nodes(raw: &J) -> Result<Vec<F3dNode>, ImportError> {
    let mut nodes = Vec::new();
    for (k, n) in part(raw, "nodes_info")?.into_iter().flatten() {
        let id = f3d_id(k, n, "node")?;
        nodes.push(F3dNode {
            id,
            id_name: n
                .get("id_name")
                .and_then(|v| v.as_str())
                .unwrap_or("")
                .to_string(),
            inputs: sockets_in_order(n.get("inputs")),
            outputs: sockets_in_order(n.get("outputs")),
        });
    }
    nodes.sort_by_key(|n| n.id);
    Ok(nodes)
}

/// `links_info` as (link id, start socket, end socket), in id order.
fn read_links(raw: &J) -> Result<Vec<(i64, i64, i64)>, ImportError> {
    let mut links: Vec<(i64, i64, i64)> = part(raw, "links_info")?
        .into_iter()
        .flat_map(|o| o.values())
        .filter_map(|l| {
            Some((
                l.get("ID")?.as_i64()?,
                l.get("StartPinID")?.as_i64()?,
                l.get("EndPinID")?.as_i64()?,
            ))
        })
        .collect();
    links.sort();
    Ok(links)
}

/// Fails naming every node whose `id_name` has no map, all at once.
fn check_known(nodes: &[F3dNode], maps: &BTreeMap<String, NodeMap>) -> Result<(), ImportError> {
    let unknown: Vec<String> = nodes
        .iter()
        .filter(|n| !maps.contains_key(&n.id_name))
        .map(|n| format!("{} (node {})", n.id_name, n.id))
        .collect();
    if unknown.is_empty() {
        return Ok(());
    }
    Err(ImportError(format!(
        "unknown Framework3D nodes: {}. Map them onto cgnodes nodes with --f3d-aliases FILE (see docs/framework3d.md)",
        unknown.join(", ")
    )))
}

/// The warnings known before converting: an empty graph, nodes not run in a batch.
fn start_warnings(nodes: &[F3dNode], maps: &BTreeMap<String, NodeMap>) -> Vec<String> {
    let mut warnings: Vec<String> = Vec::new();
    if nodes.is_empty() {
        warnings.push("the graph is empty (no nodes saved)".into());
    }
    warnings.extend(nodes.iter().filter_map(|n| {
        let why = maps[&n.id_name].unsupported.as_ref()?;
        Some(format!("{} (node {}) is not run: {why}", n.id_name, n.id))
    }));
    warnings
}

/// One line per cgnodes node type (target or helper) missing from `registry`.
fn missing_targets(
    nodes: &[F3dNode],
    maps: &BTreeMap<String, NodeMap>,
    registry: &Registry,
) -> Result<Vec<String>, ImportError> {
    let mut missing = Vec::new();
    for n in nodes {
        let m = &maps[&n.id_name];
        let mut need: Vec<&str> = m.node_type.iter().map(String::as_str).collect();
        for t in m.inputs.values().chain(m.outputs.values()).flatten() {
            if let Some((_, h)) = t.split_once(['<', '>']) {
                need.push(helper(h)?.0);
            }
        }
        for f in m.feeds.values() {
            need.push(feed(f)?.0);
        }
        for t in need {
            if registry.get(t).is_none() {
                missing.push(format!("{} (node {}) needs '{t}'", n.id_name, n.id));
            }
        }
    }
    Ok(missing)
}

/// Socket id -> (index in `nodes`, whether an input).
fn owners(nodes: &[F3dNode]) -> BTreeMap<i64, (usize, bool)> {
    let mut owner = BTreeMap::new();
    for (i, n) in nodes.iter().enumerate() {
        for &s in &n.inputs {
            owner.insert(s, (i, true));
        }
        for &s in &n.outputs {
            owner.insert(s, (i, false));
        }
    }
    owner
}

/// A helper node with no parameters or links yet.
fn bare(node_type: &str) -> NodeSpec {
    NodeSpec {
        node_type: node_type.to_string(),
        params: BTreeMap::new(),
        inputs: BTreeMap::new(),
        meta: None,
    }
}

/// The graph being built and what building it reads.
struct Builder<'a> {
    raw: &'a J,
    maps: &'a BTreeMap<String, NodeMap>,
    registry: &'a Registry,
    sockets: BTreeMap<i64, F3dSocket>,
    nodes: &'a [F3dNode],
    /// Socket id -> (index in `nodes`, whether an input).
    owner: BTreeMap<i64, (usize, bool)>,
    /// Sockets some link ends at (their widget values are not used).
    link_ends: BTreeSet<i64>,
    /// The file each Write USD node writes, by Framework3D node id.
    usd_paths: BTreeMap<i64, String>,
    out_nodes: BTreeMap<String, NodeSpec>,
    warnings: Vec<String>,
}

impl<'a> Builder<'a> {
    fn node_id(n: &F3dNode) -> String {
        format!("{}_{}", short_name(&n.id_name), n.id)
    }

    fn map(&self, n: &F3dNode) -> &'a NodeMap {
        &self.maps[&n.id_name]
    }

    /// The target node's declaration, when this build has it.
    fn decl(&self, n: &F3dNode) -> Option<&'a NodeDecl> {
        self.map(n)
            .node_type
            .as_ref()
            .and_then(|t| self.registry.get(t))
            .map(|d| &**d)
    }

    fn sock_err(n: &F3dNode, what: &str, ident: &str) -> ImportError {
        ImportError(format!(
            "{} (node {}) has {what} '{ident}' with no cgnodes counterpart; map it with --f3d-aliases",
            n.id_name, n.id
        ))
    }

    /// The node's spec: its type, fixed parameters, meta and the widget values of its
    /// unlinked inputs.
    fn add_node(&mut self, n: &F3dNode) -> Result<(), ImportError> {
        let m = self.map(n);
        let Some(ty) = &m.node_type else {
            return Ok(());
        };
        let mut meta = serde_json::json!({"f3d_id": n.id, "f3d_id_name": n.id_name});
        if let Some(note) = &m.note {
            meta["note"] = serde_json::json!(note);
        }
        if let Some(loc) = self
            .raw
            .get("nodes")
            .and_then(|v| v.get(format!("node:{}", n.id)))
            .and_then(|v| v.get("location"))
        {
            meta["location"] = loc.clone();
        }
        let mut spec = NodeSpec {
            node_type: ty.clone(),
            params: m.params.clone(),
            inputs: BTreeMap::new(),
            meta: Some(meta),
        };
        for &s in &n.inputs {
            self.add_widget(n, s, &mut spec)?;
        }
        self.out_nodes.insert(Self::node_id(n), spec);
        Ok(())
    }

    /// The widget value of input socket `s` of `n` (unless linked, dropped or unmapped) as a
    /// parameter of `spec`: one component of a vector, the input of a helper, or a literal.
    fn add_widget(&mut self, n: &F3dNode, s: i64, spec: &mut NodeSpec) -> Result<(), ImportError> {
        let sock = self.sockets.get(&s).ok_or_else(|| {
            ImportError(format!(
                "node {} ({}) names input socket {s}, which sockets_info does not list",
                n.id, n.id_name
            ))
        })?;
        if self.link_ends.contains(&s) {
            return Ok(());
        }
        let Some(v) = &sock.value else { return Ok(()) };
        let target = match self.map(n).inputs.get(&sock.identifier) {
            Some(Some(t)) => t.clone(),
            _ => return Ok(()), // dropped or unmapped: the widget value is not used
        };
        let Some(v) = self.translate(n, sock, v)? else {
            return Ok(());
        };
        if let Some((base, k)) = component(&target) {
            return self.set_component(n, sock, &v, (base, k), spec);
        }
        if let Some((sock_name, helper_spec)) = target.split_once('<') {
            let (htype, hin, hout) = helper(helper_spec)?;
            let hid = format!("{}_{}", Self::node_id(n), htype);
            let mut h = bare(htype);
            h.params.insert(hin.to_string(), v);
            self.out_nodes.insert(hid.clone(), h);
            spec.inputs.insert(
                sock_name.to_string(),
                LinkSpec::One(format!("{hid}.{hout}")),
            );
            return Ok(());
        }
        let ty = match self.decl(n) {
            Some(d) => match d.input(&target) {
                Some(s) => Some(s.ty.clone()),
                None => return Err(Self::sock_err(n, "input", &sock.identifier)),
            },
            None => None, // node missing from this build: keep the value as is
        };
        let mut lit = literal(&v, ty.as_ref()).unwrap_or(v.clone());
        if n.id_name == "geom_write_usd" && target == "path" {
            lit = serde_json::json!(self
                .usd_paths
                .get(&n.id)
                .cloned()
                .unwrap_or_else(|| write_usd_path(lit.as_str().unwrap_or(""))));
        }
        spec.params.insert(target, lit);
        Ok(())
    }

    /// A widget value through the map's translation table for its socket (a switch choosing
    /// an integrator, ...); `None` when the table says to leave the socket alone.
    fn translate(&self, n: &F3dNode, sock: &F3dSocket, v: &J) -> Result<Option<J>, ImportError> {
        let Some(table) = self.map(n).values.get(&sock.identifier) else {
            return Ok(Some(v.clone()));
        };
        match table.get(&value_key(v)) {
            Some(J::Null) => Ok(None),
            Some(t) => Ok(Some(t.clone())),
            None => Err(ImportError(format!(
                "{} (node {}) has '{}' = {} which cgnodes does not translate (known: {})",
                n.id_name,
                n.id,
                sock.identifier,
                value_key(v),
                table.keys().cloned().collect::<Vec<_>>().join(", ")
            ))),
        }
    }

    /// One component of a vector socket (Translate X -> translate[0]), starting from the
    /// parameter set so far or the socket's default.
    fn set_component(
        &self,
        n: &F3dNode,
        sock: &F3dSocket,
        v: &J,
        (base, k): (&str, usize),
        spec: &mut NodeSpec,
    ) -> Result<(), ImportError> {
        let x = v.as_f64().ok_or_else(|| {
            ImportError(format!(
                "{} (node {}) has '{}' = {v}, not a number",
                n.id_name, n.id, sock.identifier
            ))
        })?;
        let start = spec.params.get(base).cloned().or_else(|| {
            self.decl(n)
                .and_then(|d| d.input(base))
                .and_then(|s| s.default_value())
                .and_then(|v| v.to_json())
        });
        let mut arr = match start {
            Some(J::Array(a)) => a,
            _ => vec![serde_json::json!(0.0); 3],
        };
        if k >= arr.len() {
            return Err(Self::sock_err(n, "input", &sock.identifier));
        }
        arr[k] = serde_json::json!(x);
        spec.params.insert(base.to_string(), J::Array(arr));
        Ok(())
    }

    /// Link `lid` from socket `from` to socket `to`, unless it ends in a removed node or
    /// socket, or starts at a node or output that is not run (with a warning).
    fn add_link(&mut self, lid: i64, from: i64, to: i64) -> Result<(), ImportError> {
        let (Some(&(fi, false)), Some(&(ti, true))) = (self.owner.get(&from), self.owner.get(&to))
        else {
            return Err(ImportError(format!(
                "link {lid} does not run from an output socket to an input socket"
            )));
        };
        let (fnode, tnode) = (&self.nodes[fi], &self.nodes[ti]);
        let (fmap, tmap) = (self.map(fnode), self.map(tnode));
        let socket = |id: i64| {
            self.sockets
                .get(&id)
                .map(|s| s.identifier.clone())
                .ok_or_else(|| {
                    ImportError(format!(
                        "link {lid} names socket {id}, which sockets_info does not list"
                    ))
                })
        };
        let (fsock, tsock) = (socket(from)?, socket(to)?);
        if tmap.node_type.is_none() {
            return Ok(()); // into a removed node (storage, time gain)
        }
        let target = match tmap.inputs.get(&tsock) {
            Some(None) => return Ok(()), // a state or time socket the executor replaces
            Some(Some(t)) => t.clone(),
            None => return Err(Self::sock_err(tnode, "linked input", &tsock)),
        };
        if fmap.unsupported.is_some() {
            self.warnings.push(format!(
                "{} (node {}) input '{tsock}' keeps its default: it was fed by {} (node {}), which is not run",
                tnode.id_name, tnode.id, fnode.id_name, fnode.id
            ));
            return Ok(());
        }
        if fmap.node_type.is_none() {
            return Err(ImportError(format!(
                "{} (node {}) input '{tsock}' is fed by {} (node {}), which cgnodes replaces by its frame executor; connect it to the node's own output instead",
                tnode.id_name, tnode.id, fnode.id_name, fnode.id
            )));
        }
        let source = match fmap.outputs.get(&fsock) {
            Some(Some(s)) => s.clone(),
            Some(None) => {
                // an output the map drops on purpose (e.g. the rasterizer's MetallicRoughness)
                self.warnings.push(format!(
                    "{} (node {}) input '{tsock}' keeps its default: output '{fsock}' of {} (node {}) has no cgnodes counterpart",
                    tnode.id_name, tnode.id, fnode.id_name, fnode.id
                ));
                return Ok(());
            }
            None => return Err(Self::sock_err(fnode, "output", &fsock)),
        };
        let src = self.link_source(fnode, &source)?;
        let (tnode_id, tsocket) = self.link_target(tnode, target)?;
        self.connect(&tnode_id, tsocket, src);
        Ok(())
    }

    /// `node.output` a link from output `source` of `fnode` starts at, through the output's
    /// helper node when the map gives one.
    fn link_source(&mut self, fnode: &F3dNode, source: &str) -> Result<String, ImportError> {
        let fid = Self::node_id(fnode);
        let Some((s, helper_spec)) = source.split_once('>') else {
            return Ok(format!("{fid}.{source}"));
        };
        let (htype, hin, hout) = helper(helper_spec)?;
        let hid = format!("{fid}_{htype}");
        let mut h = bare(htype);
        h.inputs
            .insert(hin.to_string(), LinkSpec::One(format!("{fid}.{s}")));
        self.out_nodes.insert(hid.clone(), h);
        Ok(format!("{hid}.{hout}"))
    }

    /// The (node, input) a link into `target` of `tnode` ends at: a link into a helper-fed
    /// socket goes into the helper's input.
    fn link_target(
        &mut self,
        tnode: &F3dNode,
        target: String,
    ) -> Result<(String, String), ImportError> {
        let tid = Self::node_id(tnode);
        let Some((s, helper_spec)) = target.split_once('<') else {
            return Ok((tid, target));
        };
        let (htype, hin, hout) = helper(helper_spec)?;
        let hid = format!("{tid}_{htype}");
        self.out_nodes
            .entry(hid.clone())
            .or_insert_with(|| bare(htype));
        if let Some(t) = self.out_nodes.get_mut(&tid) {
            t.inputs
                .insert(s.to_string(), LinkSpec::One(format!("{hid}.{hout}")));
        }
        Ok((hid, hin.to_string()))
    }

    /// Links `src` into `socket` of node `id`, replacing a widget value; a second link into
    /// the same socket makes it a list.
    fn connect(&mut self, id: &str, socket: String, src: String) {
        let Some(t) = self.out_nodes.get_mut(id) else {
            return;
        };
        t.params.remove(&socket);
        let links = match t.inputs.remove(&socket) {
            None => LinkSpec::One(src),
            Some(LinkSpec::One(prev)) => LinkSpec::Many(vec![prev, src]),
            Some(LinkSpec::Many(mut v)) => {
                v.push(src);
                LinkSpec::Many(v)
            }
        };
        t.inputs.insert(socket, links);
    }

    /// Inputs of `n` fed by a helper of their own, unless a widget or link already set them.
    fn add_feeds(&mut self, n: &F3dNode) -> Result<(), ImportError> {
        let id = Self::node_id(n);
        for (sock, f) in &self.map(n).feeds {
            let (htype, hout) = feed(f)?;
            let Some(spec) = self.out_nodes.get(&id) else {
                continue;
            };
            if spec.params.contains_key(sock) || spec.inputs.contains_key(sock) {
                continue;
            }
            let hid = format!("{id}_{htype}");
            self.out_nodes.insert(hid.clone(), bare(htype));
            if let Some(spec) = self.out_nodes.get_mut(&id) {
                spec.inputs
                    .insert(sock.clone(), LinkSpec::One(format!("{hid}.{hout}")));
            }
        }
        Ok(())
    }

    /// The graph, with the warnings in its meta.
    fn finish(self) -> GraphFile {
        let mut meta = serde_json::json!({ "imported_from": IMPORTED_FROM });
        if !self.warnings.is_empty() {
            meta["f3d_warnings"] = serde_json::json!(self.warnings);
        }
        GraphFile {
            schema: None,
            format: FORMAT.to_string(),
            version: VERSION,
            nodes: self.out_nodes,
            outputs: None,
            meta: Some(meta),
        }
    }
}
