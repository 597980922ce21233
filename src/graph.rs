//! The graph file format (version 1), its loading, version migration and JSON Schema.
//! See `docs/graph-format.md`.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The value of the `format` field.
pub const FORMAT: &str = "cgnodes-graph";
/// The newest format version this build reads and writes.
pub const VERSION: u32 = 1;

/// A graph file: nodes by id, with literal parameters and links.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GraphFile {
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
}

/// Why a graph file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file could not be read.
    #[error("{file}: {source}")]
    Io {
        file: PathBuf,
        source: std::io::Error,
    },
    /// The JSON is malformed or does not fit the format.
    #[error("{file}:{line}:{column}: {message}")]
    Parse {
        file: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    /// The file is JSON but not a graph this build reads.
    #[error("{file}: {message}")]
    Format { file: PathBuf, message: String },
}

/// Loads a graph file: a cgnodes graph of any supported version, or a Framework3D saved
/// node tree (recognised by its `nodes_info`, `sockets_info` and `links_info` keys).
pub fn load(path: &Path) -> Result<Graph, LoadError> {
    load_with(path, &crate::f3d::Aliases::default())
}

/// Like `load`, with aliases mapping custom Framework3D node names (`--f3d-aliases`).
pub fn load_with(path: &Path, aliases: &crate::f3d::Aliases) -> Result<Graph, LoadError> {
    let text = std::fs::read_to_string(path).map_err(|e| LoadError::Io {
        file: path.to_path_buf(),
        source: e,
    })?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let dir = if dir.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        dir
    };
    parse_with(&text, path, &dir, aliases)
}

/// Parses graph text; `file` labels errors, `dir` is where relative paths resolve.
pub fn parse(text: &str, file: &Path, dir: &Path) -> Result<Graph, LoadError> {
    parse_with(text, file, dir, &crate::f3d::Aliases::default())
}

/// Like `parse`, with aliases for custom Framework3D node names.
pub fn parse_with(
    text: &str,
    file: &Path,
    dir: &Path,
    aliases: &crate::f3d::Aliases,
) -> Result<Graph, LoadError> {
    let perr = |e: serde_json::Error| LoadError::Parse {
        file: file.to_path_buf(),
        line: e.line(),
        column: e.column(),
        message: e
            .to_string()
            .split(" at line ")
            .next()
            .unwrap_or_default()
            .to_string(),
    };
    let raw: serde_json::Value = serde_json::from_str(text).map_err(perr)?;
    let ferr = |m: String| LoadError::Format {
        file: file.to_path_buf(),
        message: m,
    };
    let obj = raw
        .as_object()
        .ok_or_else(|| ferr("a graph file is a JSON object".into()))?;
    if crate::f3d::is_f3d(&raw) {
        let spec = crate::f3d::import(&raw, aliases).map_err(|e| ferr(e.to_string()))?;
        return Ok(Graph {
            file: file.to_path_buf(),
            dir: dir.to_path_buf(),
            spec,
        });
    }
    match obj.get("format").and_then(|f| f.as_str()) {
        Some(FORMAT) => {}
        Some(other) => return Err(ferr(format!("format is '{other}', expected '{FORMAT}'"))),
        None => {
            return Err(ferr(format!(
                "missing \"format\": \"{FORMAT}\" (or a Framework3D node tree)"
            )))
        }
    }
    let version = obj
        .get("version")
        .and_then(|v| v.as_u64())
        .ok_or_else(|| ferr("missing or non-integer \"version\"".into()))? as u32;
    let spec: GraphFile = if version == VERSION {
        // Deserialize from the text so errors keep their line and column.
        serde_json::from_str(text).map_err(perr)?
    } else if version > VERSION {
        return Err(ferr(format!(
            "version {version} is newer than this cgnodes reads ({VERSION}); please upgrade"
        )));
    } else {
        let migrated = migrate(raw, version).map_err(ferr)?;
        serde_json::from_value(migrated).map_err(|e| ferr(e.to_string()))?
    };
    Ok(Graph {
        file: file.to_path_buf(),
        dir: dir.to_path_buf(),
        spec,
    })
}

/// Migrates a raw graph of an older version to the current one, one version at a time.
/// Version 1 is the first; later versions add steps here so old files keep working.
pub fn migrate(raw: serde_json::Value, from: u32) -> Result<serde_json::Value, String> {
    // Each step rewrites version N into N + 1 (for example `1 => migrate_1_to_2(v)`).
    // Version 1 is the first, so there is no step yet.
    if from < VERSION {
        return Err(format!("no migration from version {from}"));
    }
    Ok(raw)
}

/// The JSON Schema of the graph format (`cgnodes schema`).
pub fn schema() -> serde_json::Value {
    let s = schemars::schema_for!(GraphFile);
    serde_json::to_value(s).unwrap_or_default()
}

impl GraphFile {
    /// The frame range the graph suggests in `meta.frames` (`"A..B"`), used when the command
    /// line gives no `--frames`.
    pub fn frames_hint(&self) -> Option<(i64, i64)> {
        let f = self.meta.as_ref()?.get("frames")?.as_str()?;
        crate::cli::parse_frames(f).ok()
    }
}

/// Parses `"node.socket"`.
pub fn split_link(s: &str) -> Option<(&str, &str)> {
    let (n, k) = s.rsplit_once('.')?;
    (!n.is_empty() && !k.is_empty()).then_some((n, k))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_errors_carry_line_and_column() {
        let e = parse(
            "{\n  \"format\": \"cgnodes-graph\",\n  \"version\": 1,\n  \"nodes\": {,}\n}",
            Path::new("g.json"),
            Path::new("."),
        )
        .unwrap_err();
        match e {
            LoadError::Parse { line, column, .. } => {
                assert_eq!(line, 4);
                assert!(column > 1);
            }
            other => panic!("{other}"),
        }
    }

    #[test]
    fn unknown_fields_are_errors() {
        let t = r#"{"format":"cgnodes-graph","version":1,"nodes":{"a":{"type":"x","param":{}}}}"#;
        let e = parse(t, Path::new("g.json"), Path::new("."))
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown field `param`"), "{e}");
    }

    #[test]
    fn newer_versions_are_refused() {
        let t = r#"{"format":"cgnodes-graph","version":9,"nodes":{}}"#;
        assert!(parse(t, Path::new("g.json"), Path::new("."))
            .unwrap_err()
            .to_string()
            .contains("newer"));
    }
}
