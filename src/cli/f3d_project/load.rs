//! Loading one graph of a project folder: missing, empty (a 0-byte file or Framework3D's
//! `null` parts), or imported against the registry, with errors naming the file.

use super::ProjectError;
use crate::f3d::Aliases;
use crate::graph::format::GraphFile;
use crate::registry::Registry;
use std::path::{Path, PathBuf};

/// One of a project's graph files.
pub(super) enum ProjectGraph {
    /// The file is not in the folder.
    Missing,
    /// The file is there but holds no nodes.
    Empty,
    /// The imported graph with its raw JSON and the file.
    Graph {
        file: PathBuf,
        raw: serde_json::Value,
        spec: Box<GraphFile>,
        hash: String,
    },
}

/// Reads and imports `dir/name`.
pub(super) fn load_project_graph(
    dir: &Path,
    name: &str,
    aliases: &Aliases,
    registry: &Registry,
) -> Result<ProjectGraph, ProjectError> {
    let file = dir.join(name);
    if !file.exists() {
        return Ok(ProjectGraph::Missing);
    }
    let invalid = ProjectError::Invalid;
    let bytes = std::fs::read(&file).map_err(|e| invalid(format!("{}: {e}", file.display())))?;
    let text = String::from_utf8_lossy(&bytes);
    if text.trim().is_empty() {
        return Ok(ProjectGraph::Empty);
    }
    let raw: serde_json::Value = crate::io::json::parse_strict(&text)
        .map_err(|e| invalid(format!("{}: not JSON: {e}", file.display())))?;
    if raw.is_null() {
        return Ok(ProjectGraph::Empty);
    }
    if !crate::f3d::is_f3d(&raw) {
        return Err(invalid(format!(
            "{}: not a Framework3D saved node tree (no nodes_info, sockets_info, links_info)",
            file.display()
        )));
    }
    let nodes = raw.get("nodes_info");
    if nodes.is_some_and(|n| n.is_null() || n.as_object().is_some_and(|o| o.is_empty())) {
        return Ok(ProjectGraph::Empty);
    }
    let spec = crate::f3d::import(&raw, aliases, registry)
        .map_err(|e| invalid(format!("{}: {e}", file.display())))?;
    for w in crate::f3d::warnings(&spec) {
        eprintln!("warning: {}: {w}", file.display());
    }
    Ok(ProjectGraph::Graph {
        file,
        raw,
        spec: Box::new(spec),
        hash: crate::node::Provenance::hash_graph(&bytes),
    })
}
