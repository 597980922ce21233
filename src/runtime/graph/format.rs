//! The graph file format (version 1): the serde types of a graph file, version migration
//! and the JSON Schema. Loading a file (which may be a Framework3D tree and then needs a
//! registry) is in `graph::load`. See `docs/graph-format.md`.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// The value of the `format` field.
pub const FORMAT: &str = "cgnodes-graph";
/// The newest format version this build reads and writes.
pub const VERSION: u32 = 1;

/// A graph file: nodes by id, with literal parameters and links.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GraphFile {
    /// The JSON Schema editors check the file against (`docs/graph.schema.json`); ignored by
    /// the runtime, accepted so that an editor can attach the schema.
    #[serde(rename = "$schema", default, skip_serializing_if = "Option::is_none")]
    pub schema: Option<String>,
    /// Always `cgnodes-graph`.
    pub format: String,
    /// Format version (1).
    pub version: u32,
    /// Nodes by id.
    pub nodes: BTreeMap<String, NodeSpec>,
    /// Node ids to evaluate; default: every sink node (writers, `print`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outputs: Option<Vec<String>>,
    /// Free-form data (editor positions, notes); ignored by the runtime.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub meta: Option<serde_json::Value>,
}

/// One node of a graph.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct NodeSpec {
    /// Node type, as `cgnodes nodes` lists them.
    #[serde(rename = "type")]
    pub node_type: String,
    /// Literal values of input sockets.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub params: BTreeMap<String, serde_json::Value>,
    /// Links into input sockets: `"<node id>.<output socket>"`, or a list of them for a list socket.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub inputs: BTreeMap<String, LinkSpec>,
    /// Free-form data (editor position); ignored by the runtime.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub meta: Option<serde_json::Value>,
}

/// One link or several (for list sockets).
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(untagged)]
pub enum LinkSpec {
    /// `"<node id>.<output socket>"`.
    One(String),
    /// Several links into one list socket, in order.
    Many(Vec<String>),
}

impl LinkSpec {
    /// The links as a list.
    pub fn links(&self) -> Vec<&str> {
        match self {
            LinkSpec::One(s) => vec![s.as_str()],
            LinkSpec::Many(v) => v.iter().map(String::as_str).collect(),
        }
    }
}

/// A graph loaded from a file, with the folder its relative paths resolve against.
#[derive(Clone, Debug)]
pub struct Graph {
    /// The file it came from (or a label such as `<string>`).
    pub file: PathBuf,
    /// The folder relative input paths resolve against.
    pub dir: PathBuf,
    /// The graph itself.
    pub spec: GraphFile,
    /// `blake3:HEX` of the bytes the graph was read from (`node::Provenance::graph_hash`).
    pub hash: String,
}

/// Why an older graph could not be migrated to the current version.
#[derive(Debug, thiserror::Error)]
pub enum MigrateError {
    /// No migration step starts at this version.
    #[error("no migration from version {from}")]
    NoStep {
        /// The file's version.
        from: u32,
    },
}

/// Migrates a raw graph of an older version to the current one, one version at a time.
/// Version 1 is the first; later versions add steps here so old files keep working.
pub fn migrate(raw: serde_json::Value, from: u32) -> Result<serde_json::Value, MigrateError> {
    // Each step rewrites version N into N + 1 (for example `1 => migrate_1_to_2(v)`).
    // Version 1 is the first, so there is no step yet.
    if from < VERSION {
        return Err(MigrateError::NoStep { from });
    }
    Ok(raw)
}

/// The JSON Schema of the graph format (`cgnodes schema`).
pub fn schema() -> serde_json::Value {
    let s = schemars::schema_for!(GraphFile);
    serde_json::to_value(s).unwrap_or_default()
}

/// Parses `"node.socket"`.
pub fn split_link(s: &str) -> Option<(&str, &str)> {
    let (n, k) = s.rsplit_once('.')?;
    (!n.is_empty() && !k.is_empty()).then_some((n, k))
}
