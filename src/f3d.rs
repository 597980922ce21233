//! Framework3D (USTC CG 2024) saved node trees: detection and import into the native format.
//! See `docs/framework3d.md`.

use crate::graph::GraphFile;
use std::collections::BTreeMap;

/// User aliases mapping Framework3D `id_name`s onto cgnodes nodes (`--f3d-aliases FILE`).
#[derive(Clone, Debug, Default, serde::Deserialize)]
pub struct Aliases {
    /// By Framework3D `id_name`.
    #[serde(flatten)]
    pub nodes: BTreeMap<String, serde_json::Value>,
}

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

/// Converts a Framework3D saved node tree into a cgnodes graph.
pub fn import(_raw: &serde_json::Value, _aliases: &Aliases) -> Result<GraphFile, ImportError> {
    Err(ImportError(
        "importing Framework3D graphs is not implemented yet".into(),
    ))
}
