//! Framework3D (USTC CG 2024) saved node trees: detection and import into the native format.
//! See `docs/framework3d.md`.
//!
//! Each Framework3D `id_name` maps onto a cgnodes node through a `NodeMap`: the node type,
//! fixed parameters, and where each Framework3D socket (by its `identifier`) goes. The
//! built-in maps are the JSON in `BUILTIN`; a user's alias file (`--f3d-aliases FILE`) has
//! the same shape and overrides or extends them. Widget values of unlinked inputs become
//! parameters; links become links. Storage and time-gain nodes are removed (the frame
//! executor keeps simulation state between frames), as are the state sockets they feed.

use crate::graph::format::GraphFile;
use cgnodes_api::registry::Registry;
use serde::Deserialize;
use std::collections::BTreeMap;

mod builtin;
mod convert;
mod names;
pub mod present;
pub mod table;
mod util;

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
    convert::convert(raw, &node_maps(aliases)?, registry, strict)
}
