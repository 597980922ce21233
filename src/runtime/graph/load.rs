//! Loading a graph file: a cgnodes graph of any supported version (migrated to the current
//! one), or a Framework3D saved node tree, which is imported against a node registry so
//! that its nodes (and the targets of `--f3d-aliases`) can be built-in or plugin nodes.

use super::format::{migrate, Graph, GraphFile, FORMAT, VERSION};
use crate::f3d::{self, Aliases};
use cgnodes_api::registry::Registry;
use std::path::{Path, PathBuf};

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

/// Loads a cgnodes graph file of any supported version. A Framework3D node tree needs a
/// registry to import against: load it with `load_with`.
pub fn load(path: &Path) -> Result<Graph, LoadError> {
    let (text, dir) = read(path)?;
    parse_any(&text, path, &dir, None)
}

/// Loads a graph file: a cgnodes graph of any supported version, or a Framework3D saved
/// node tree (recognised by its `nodes_info`, `sockets_info` and `links_info` keys), imported
/// with `aliases` (`--f3d-aliases`) onto the nodes of `registry`.
pub fn load_with(path: &Path, aliases: &Aliases, registry: &Registry) -> Result<Graph, LoadError> {
    let (text, dir) = read(path)?;
    parse_any(&text, path, &dir, Some((aliases, registry)))
}

/// The text of `path` and the folder its relative paths resolve against.
fn read(path: &Path) -> Result<(String, PathBuf), LoadError> {
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
    Ok((text, dir))
}

/// Parses cgnodes graph text; `file` labels errors, `dir` is where relative paths resolve.
pub fn parse(text: &str, file: &Path, dir: &Path) -> Result<Graph, LoadError> {
    parse_any(text, file, dir, None)
}

/// Like `parse`, also reading Framework3D node trees (imported with `aliases` onto the
/// nodes of `registry`).
pub fn parse_with(
    text: &str,
    file: &Path,
    dir: &Path,
    aliases: &Aliases,
    registry: &Registry,
) -> Result<Graph, LoadError> {
    parse_any(text, file, dir, Some((aliases, registry)))
}

fn parse_any(
    text: &str,
    file: &Path,
    dir: &Path,
    f3d_with: Option<(&Aliases, &Registry)>,
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
    // Strict: the same node id, param or input twice is an error naming the key and line.
    let raw: serde_json::Value = cgnodes_api::io::json::parse_strict(text).map_err(perr)?;
    let ferr = |m: String| LoadError::Format {
        file: file.to_path_buf(),
        message: m,
    };
    let obj = raw
        .as_object()
        .ok_or_else(|| ferr("a graph file is a JSON object".into()))?;
    if f3d::is_f3d(&raw) {
        let Some((aliases, registry)) = f3d_with else {
            return Err(ferr(
                "a Framework3D node tree needs a node registry to import against (graph::load_with)"
                    .into(),
            ));
        };
        let spec = f3d::import(&raw, aliases, registry).map_err(|e| ferr(e.to_string()))?;
        for w in f3d::warnings(&spec) {
            eprintln!("warning: {}: {w}", file.display());
        }
        return Ok(Graph {
            file: file.to_path_buf(),
            dir: dir.to_path_buf(),
            spec,
            hash: cgnodes_api::node::Provenance::hash_graph(text.as_bytes()),
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
        let migrated = migrate(raw, version).map_err(|e| ferr(e.to_string()))?;
        serde_json::from_value(migrated).map_err(|e| ferr(e.to_string()))?
    };
    Ok(Graph {
        file: file.to_path_buf(),
        dir: dir.to_path_buf(),
        spec,
        hash: cgnodes_api::node::Provenance::hash_graph(text.as_bytes()),
    })
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
