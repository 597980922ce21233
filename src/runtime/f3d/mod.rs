//! Framework3D (USTC CG 2024) saved node trees: detection and import into the native format.
//! See `docs/framework3d.md`.
//!
//! Each Framework3D `id_name` maps onto a cgnodes node through a `NodeMap`: the node type,
//! fixed parameters, and where each Framework3D socket (by its `identifier`) goes. The
//! built-in maps are the JSON in `BUILTIN`; a user's alias file (`--f3d-aliases FILE`) has
//! the same shape and overrides or extends them. Widget values of unlinked inputs become
//! parameters; links become links. Storage and time-gain nodes are removed (the frame
//! executor keeps simulation state between frames), as are the state sockets they feed.

use crate::graph::format::{GraphFile, LinkSpec, NodeSpec, FORMAT, VERSION};
use cgnodes_api::node::NodeDecl;
use cgnodes_api::registry::Registry;
use serde::Deserialize;
use std::collections::BTreeMap;

mod builtin;
mod names;
pub mod present;
pub mod table;
mod util;
use names::{write_usd_path, write_usd_paths};
use util::{component, f3d_id, feed, helper, literal, short_name, sockets_in_order, value_key};

/// User aliases mapping Framework3D `id_name`s onto cgnodes nodes (`--f3d-aliases FILE`):
/// `{"<id_name>": <NodeMap>, ...}`; keys starting with `_` (comments) are ignored.
#[derive(Clone, Debug, Default, serde::Deserialize)]
pub struct Aliases {
    /// By Framework3D `id_name`.
    #[serde(flatten)]
    pub nodes: BTreeMap<String, serde_json::Value>,
}

/// How one Framework3D node becomes a cgnodes node.
///
/// Socket targets are a cgnodes socket name, `null` (dropped: a link from a dropped output
/// leaves the input it fed at its default, with a warning), or for inputs
/// `"socket<helper.in:out"` (the Framework3D value or link goes into input `in` of a helper
/// node whose output `out` feeds `socket`, e.g. `image<image_load.path:image`), and for
/// outputs `"socket>helper.in:out"` (output `socket` passes through a helper node, e.g.
/// `mesh>mesh_decompose.mesh:texcoords`).
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeMap {
    /// cgnodes node type; absent or null when the node is removed.
    #[serde(rename = "type", default)]
    pub node_type: Option<String>,
    /// Literal parameters always set.
    #[serde(default)]
    pub params: BTreeMap<String, serde_json::Value>,
    /// Framework3D input identifier -> cgnodes input.
    #[serde(default)]
    pub inputs: BTreeMap<String, Option<String>>,
    /// Framework3D output identifier -> cgnodes output.
    #[serde(default)]
    pub outputs: BTreeMap<String, Option<String>>,
    /// Widget value translations by Framework3D input identifier: the widget's value (as text:
    /// `0`, `1`, `0.5`, a string) -> the cgnodes literal, or `null` to leave the socket alone
    /// (e.g. `"enable Liu13": {"0": null, "1": "projective"}` into `integrator`).
    #[serde(default)]
    pub values: BTreeMap<String, BTreeMap<String, serde_json::Value>>,
    /// cgnodes inputs fed by a helper node of their own, `"socket": "type:output"` (e.g.
    /// `"time": "frame:time"` for a node whose Framework3D version reads the global time).
    #[serde(default)]
    pub feeds: BTreeMap<String, String>,
    /// Why the map is as it is (kept in the node's meta).
    #[serde(default)]
    pub note: Option<String>,
    /// Why the node cannot run in a batch (a GUI view, user shader code, ...): the node is
    /// left out with a warning naming it, and inputs it fed keep their defaults.
    #[serde(default)]
    pub unsupported: Option<String>,
}

/// The warnings an import left in the graph's meta (`f3d_warnings`): nodes left out as
/// unsupported in a batch run and the inputs they fed.
pub fn warnings(g: &GraphFile) -> Vec<String> {
    g.meta
        .as_ref()
        .and_then(|m| m.get("f3d_warnings"))
        .and_then(|w| w.as_array())
        .map(|a| {
            a.iter()
                .filter_map(|s| s.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default()
}

pub use builtin::BUILTIN;

/// Why a Framework3D graph could not be imported.
#[derive(Debug, thiserror::Error)]
#[error("Framework3D graph: {0}")]
pub struct ImportError(pub String);

/// Whether a JSON document is a Framework3D saved node tree.
pub fn is_f3d(raw: &serde_json::Value) -> bool {
    ["nodes_info", "sockets_info", "links_info"]
        .iter()
        .all(|k| raw.get(k).is_some())
}

/// The built-in maps, overridden and extended by `aliases`.
pub fn node_maps(aliases: &Aliases) -> Result<BTreeMap<String, NodeMap>, ImportError> {
    let mut maps: BTreeMap<String, NodeMap> =
        serde_json::from_str(BUILTIN).map_err(|e| ImportError(format!("built-in maps: {e}")))?;
    for (k, v) in &aliases.nodes {
        if k.starts_with('_') {
            continue;
        }
        let m: NodeMap = serde_json::from_value(v.clone())
            .map_err(|e| ImportError(format!("alias for '{k}': {e}")))?;
        maps.insert(k.clone(), m);
    }
    Ok(maps)
}

struct F3dSocket {
    identifier: String,
    value: Option<serde_json::Value>,
}

struct F3dNode {
    id: i64,
    id_name: String,
    inputs: Vec<i64>,
    outputs: Vec<i64>,
}

fn missing_message(missing: &[String]) -> String {
    format!(
        "cgnodes nodes missing from this build: {}",
        missing.join(", ")
    )
}

/// Converts a Framework3D saved node tree into a cgnodes graph. Target nodes and sockets
/// (built-in or plugin nodes) are checked against `registry`; fails when a target node is
/// missing, naming each with its Framework3D node id.
pub fn import(
    raw: &serde_json::Value,
    aliases: &Aliases,
    registry: &Registry,
) -> Result<GraphFile, ImportError> {
    convert(raw, aliases, registry, true).map(|(g, _)| g)
}

/// Converts even when target nodes are missing from `registry` (for `import-f3d`, so the
/// graph can be edited or run by a build that has them); returns the graph and one line per
/// missing node, naming its Framework3D id.
pub fn import_lenient(
    raw: &serde_json::Value,
    aliases: &Aliases,
    registry: &Registry,
) -> Result<(GraphFile, Vec<String>), ImportError> {
    convert(raw, aliases, registry, false)
}

fn convert(
    raw: &serde_json::Value,
    aliases: &Aliases,
    registry: &Registry,
    strict: bool,
) -> Result<(GraphFile, Vec<String>), ImportError> {
    let maps = node_maps(aliases)?;
    // Framework3D saves `null` for an empty part (no links, no nodes).
    let empty = serde_json::Map::new();
    let obj = |k: &str| match raw.get(k) {
        Some(serde_json::Value::Null) => Ok(&empty),
        v => v
            .and_then(|v| v.as_object())
            .ok_or_else(|| ImportError(format!("'{k}' is not an object"))),
    };
    let mut sockets: BTreeMap<i64, F3dSocket> = BTreeMap::new();
    for (k, s) in obj("sockets_info")? {
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
    let mut nodes: Vec<F3dNode> = Vec::new();
    for (k, n) in obj("nodes_info")? {
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
    // Unknown id_names, all at once.
    let unknown: Vec<String> = nodes
        .iter()
        .filter(|n| !maps.contains_key(&n.id_name))
        .map(|n| format!("{} (node {})", n.id_name, n.id))
        .collect();
    if !unknown.is_empty() {
        return Err(ImportError(format!(
            "unknown Framework3D nodes: {}. Map them onto cgnodes nodes with --f3d-aliases FILE (see docs/framework3d.md)",
            unknown.join(", ")
        )));
    }
    let mut warnings: Vec<String> = Vec::new();
    if nodes.is_empty() {
        warnings.push("the graph is empty (no nodes saved)".into());
    }
    warnings.extend(nodes.iter().filter_map(|n| {
        let why = maps[&n.id_name].unsupported.as_ref()?;
        Some(format!("{} (node {}) is not run: {why}", n.id_name, n.id))
    }));
    // Missing cgnodes nodes, all at once.
    let mut missing = Vec::new();
    for n in &nodes {
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
    if !missing.is_empty() && strict {
        return Err(ImportError(missing_message(&missing)));
    }
    // Socket owner: socket id -> (node index, is_input, position).
    let mut owner: BTreeMap<i64, (usize, bool)> = BTreeMap::new();
    for (i, n) in nodes.iter().enumerate() {
        for &s in &n.inputs {
            owner.insert(s, (i, true));
        }
        for &s in &n.outputs {
            owner.insert(s, (i, false));
        }
    }
    let node_id = |n: &F3dNode| format!("{}_{}", short_name(&n.id_name), n.id);
    let decl = |n: &F3dNode| -> Option<&NodeDecl> {
        maps[&n.id_name]
            .node_type
            .as_ref()
            .and_then(|t| registry.get(t))
            .map(|d| &**d)
    };
    let sock_err = |n: &F3dNode, what: &str, ident: &str| {
        ImportError(format!(
            "{} (node {}) has {what} '{ident}' with no cgnodes counterpart; map it with --f3d-aliases",
            n.id_name, n.id
        ))
    };
    let link_ends: std::collections::BTreeSet<i64> = obj("links_info")?
        .values()
        .filter_map(|l| l.get("EndPinID").and_then(|v| v.as_i64()))
        .collect();
    let usd_paths = write_usd_paths(&nodes, &sockets, &|s| link_ends.contains(&s));
    let mut out_nodes: BTreeMap<String, NodeSpec> = BTreeMap::new();
    for n in &nodes {
        let m = &maps[&n.id_name];
        let Some(ty) = &m.node_type else { continue };
        let mut meta = serde_json::json!({"f3d_id": n.id, "f3d_id_name": n.id_name});
        if let Some(note) = &m.note {
            meta["note"] = serde_json::json!(note);
        }
        if let Some(loc) = raw
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
        // Widget values of unlinked inputs become parameters.
        for &s in &n.inputs {
            let sock = sockets.get(&s).ok_or_else(|| {
                ImportError(format!(
                    "node {} ({}) names input socket {s}, which sockets_info does not list",
                    n.id, n.id_name
                ))
            })?;
            if link_ends.contains(&s) {
                continue;
            }
            let Some(v) = &sock.value else { continue };
            let target = match m.inputs.get(&sock.identifier) {
                Some(Some(t)) => t.clone(),
                _ => continue, // dropped or unmapped: the widget value is not used
            };
            // A translated widget value (a switch choosing an integrator, ...).
            let translated;
            let v = match m.values.get(&sock.identifier) {
                None => v,
                Some(table) => match table.get(&value_key(v)) {
                    Some(serde_json::Value::Null) => continue,
                    Some(t) => {
                        translated = t.clone();
                        &translated
                    }
                    None => {
                        return Err(ImportError(format!(
                        "{} (node {}) has '{}' = {} which cgnodes does not translate (known: {})",
                        n.id_name,
                        n.id,
                        sock.identifier,
                        value_key(v),
                        table.keys().cloned().collect::<Vec<_>>().join(", ")
                    )))
                    }
                },
            };
            // One component of a vector socket (Translate X -> translate[0]).
            if let Some((base, k)) = component(&target) {
                let x = v.as_f64().ok_or_else(|| {
                    ImportError(format!(
                        "{} (node {}) has '{}' = {v}, not a number",
                        n.id_name, n.id, sock.identifier
                    ))
                })?;
                let start = spec.params.get(base).cloned().or_else(|| {
                    decl(n)
                        .and_then(|d| d.input(base))
                        .and_then(|s| s.default_value())
                        .and_then(|v| v.to_json())
                });
                let mut arr = match start {
                    Some(serde_json::Value::Array(a)) => a,
                    _ => vec![serde_json::json!(0.0); 3],
                };
                if k >= arr.len() {
                    return Err(sock_err(n, "input", &sock.identifier));
                }
                arr[k] = serde_json::json!(x);
                spec.params
                    .insert(base.to_string(), serde_json::Value::Array(arr));
                continue;
            }
            if let Some((sock_name, helper_spec)) = target.split_once('<') {
                let (htype, hin, hout) = helper(helper_spec)?;
                let hid = format!("{}_{}", node_id(n), htype);
                let mut hp = BTreeMap::new();
                hp.insert(hin.to_string(), v.clone());
                out_nodes.insert(
                    hid.clone(),
                    NodeSpec {
                        node_type: htype.to_string(),
                        params: hp,
                        inputs: BTreeMap::new(),
                        meta: None,
                    },
                );
                spec.inputs.insert(
                    sock_name.to_string(),
                    LinkSpec::One(format!("{hid}.{hout}")),
                );
                continue;
            }
            let ty = match decl(n) {
                Some(d) => match d.input(&target) {
                    Some(s) => Some(s.ty.clone()),
                    None => return Err(sock_err(n, "input", &sock.identifier)),
                },
                None => None, // node missing from this build: keep the value as is
            };
            let mut lit = literal(v, ty.as_ref()).unwrap_or(v.clone());
            if n.id_name == "geom_write_usd" && target == "path" {
                lit = serde_json::json!(usd_paths
                    .get(&n.id)
                    .cloned()
                    .unwrap_or_else(|| write_usd_path(lit.as_str().unwrap_or(""))));
            }
            spec.params.insert(target, lit);
        }
        out_nodes.insert(node_id(n), spec);
    }
    // Links.
    let mut links: Vec<(i64, i64, i64)> = obj("links_info")?
        .values()
        .filter_map(|l| {
            Some((
                l.get("ID")?.as_i64()?,
                l.get("StartPinID")?.as_i64()?,
                l.get("EndPinID")?.as_i64()?,
            ))
        })
        .collect();
    links.sort();
    for (lid, from, to) in links {
        let (Some(&(fi, false)), Some(&(ti, true))) = (owner.get(&from), owner.get(&to)) else {
            return Err(ImportError(format!(
                "link {lid} does not run from an output socket to an input socket"
            )));
        };
        let (fnode, tnode) = (&nodes[fi], &nodes[ti]);
        let (fmap, tmap) = (&maps[&fnode.id_name], &maps[&tnode.id_name]);
        let socket = |id: i64| {
            sockets.get(&id).map(|s| &s.identifier).ok_or_else(|| {
                ImportError(format!(
                    "link {lid} names socket {id}, which sockets_info does not list"
                ))
            })
        };
        let (fsock, tsock) = (socket(from)?, socket(to)?);
        if tmap.node_type.is_none() {
            continue; // into a removed node (storage, time gain)
        }
        let target = match tmap.inputs.get(tsock) {
            Some(None) => continue, // a state or time socket the executor replaces
            Some(Some(t)) => t.clone(),
            None => return Err(sock_err(tnode, "linked input", tsock)),
        };
        if fmap.unsupported.is_some() {
            warnings.push(format!(
                "{} (node {}) input '{tsock}' keeps its default: it was fed by {} (node {}), which is not run",
                tnode.id_name, tnode.id, fnode.id_name, fnode.id
            ));
            continue;
        }
        if fmap.node_type.is_none() {
            return Err(ImportError(format!(
                "{} (node {}) input '{tsock}' is fed by {} (node {}), which cgnodes replaces by its frame executor; connect it to the node's own output instead",
                tnode.id_name, tnode.id, fnode.id_name, fnode.id
            )));
        }
        let source = match fmap.outputs.get(fsock) {
            Some(Some(s)) => s.clone(),
            Some(None) => {
                // an output the map drops on purpose (e.g. the rasterizer's MetallicRoughness)
                warnings.push(format!(
                    "{} (node {}) input '{tsock}' keeps its default: output '{fsock}' of {} (node {}) has no cgnodes counterpart",
                    tnode.id_name, tnode.id, fnode.id_name, fnode.id
                ));
                continue;
            }
            None => return Err(sock_err(fnode, "output", fsock)),
        };
        let fid = node_id(fnode);
        let src = if let Some((s, helper_spec)) = source.split_once('>') {
            let (htype, hin, hout) = helper(helper_spec)?;
            let hid = format!("{fid}_{htype}");
            let mut inputs = BTreeMap::new();
            inputs.insert(hin.to_string(), LinkSpec::One(format!("{fid}.{s}")));
            out_nodes.insert(
                hid.clone(),
                NodeSpec {
                    node_type: htype.to_string(),
                    params: BTreeMap::new(),
                    inputs,
                    meta: None,
                },
            );
            format!("{hid}.{hout}")
        } else {
            format!("{fid}.{source}")
        };
        let tid = node_id(tnode);
        let (tnode_id, tsocket) = if let Some((s, helper_spec)) = target.split_once('<') {
            // A link into a helper-fed socket goes into the helper's input.
            let (htype, hin, hout) = helper(helper_spec)?;
            let hid = format!("{tid}_{htype}");
            out_nodes.entry(hid.clone()).or_insert_with(|| NodeSpec {
                node_type: htype.to_string(),
                params: BTreeMap::new(),
                inputs: BTreeMap::new(),
                meta: None,
            });
            if let Some(t) = out_nodes.get_mut(&tid) {
                t.inputs
                    .insert(s.to_string(), LinkSpec::One(format!("{hid}.{hout}")));
            }
            (hid, hin.to_string())
        } else {
            (tid, target)
        };
        if let Some(t) = out_nodes.get_mut(&tnode_id) {
            t.params.remove(&tsocket);
            match t.inputs.remove(&tsocket) {
                None => {
                    t.inputs.insert(tsocket, LinkSpec::One(src));
                }
                Some(LinkSpec::One(prev)) => {
                    t.inputs.insert(tsocket, LinkSpec::Many(vec![prev, src]));
                }
                Some(LinkSpec::Many(mut v)) => {
                    v.push(src);
                    t.inputs.insert(tsocket, LinkSpec::Many(v));
                }
            }
        }
    }
    // Inputs fed by a helper of their own, unless a widget or link already set them.
    for n in &nodes {
        let m = &maps[&n.id_name];
        let id = node_id(n);
        for (sock, f) in &m.feeds {
            let (htype, hout) = feed(f)?;
            let Some(spec) = out_nodes.get(&id) else {
                continue;
            };
            if spec.params.contains_key(sock) || spec.inputs.contains_key(sock) {
                continue;
            }
            let hid = format!("{id}_{htype}");
            out_nodes.insert(
                hid.clone(),
                NodeSpec {
                    node_type: htype.to_string(),
                    params: BTreeMap::new(),
                    inputs: BTreeMap::new(),
                    meta: None,
                },
            );
            if let Some(spec) = out_nodes.get_mut(&id) {
                spec.inputs
                    .insert(sock.clone(), LinkSpec::One(format!("{hid}.{hout}")));
            }
        }
    }
    let graph = GraphFile {
        schema: None,
        format: FORMAT.to_string(),
        version: VERSION,
        nodes: out_nodes,
        outputs: None,
        meta: Some(if warnings.is_empty() {
            serde_json::json!({"imported_from": "Framework3D (USTC CG 2024) saved node tree"})
        } else {
            serde_json::json!({
                "imported_from": "Framework3D (USTC CG 2024) saved node tree",
                "f3d_warnings": warnings,
            })
        }),
    };
    Ok((graph, missing))
}
