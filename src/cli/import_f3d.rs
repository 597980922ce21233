//! `cgnodes import-f3d`: converts a Framework3D saved node tree into a cgnodes graph file.

use super::validate::read_aliases;
use super::{FileError, EXIT_INVALID};
use crate::f3d::{import_lenient, ImportError};
use crate::registry::Registry;
use std::path::Path;

/// Why `import-f3d` could not convert (or list the node maps).
#[derive(Debug, thiserror::Error)]
enum ImportF3dError {
    /// An input, aliases or output file.
    #[error(transparent)]
    File(#[from] FileError),
    /// The graph did not serialize.
    #[error("{0}")]
    Json(#[from] serde_json::Error),
    /// The aliases do not make valid node maps.
    #[error("{0}")]
    Maps(#[from] ImportError),
}

/// `cgnodes import-f3d INPUT -o OUTPUT [--f3d-aliases FILE]`. Nodes missing from
/// `registry` (built-in and plugin nodes) are reported but do not stop the conversion.
pub(super) fn cmd(registry: &Registry, input: &Path, output: &Path, aliases: Option<&Path>) -> i32 {
    let read_json = |p: &Path| -> Result<serde_json::Value, FileError> {
        let t = std::fs::read_to_string(p).map_err(FileError::at(p))?;
        crate::io::json::parse_strict(&t).map_err(FileError::at(p))
    };
    let result = (|| -> Result<(), ImportF3dError> {
        let raw = read_json(input)?;
        let al = aliases.map(read_aliases).transpose()?.unwrap_or_default();
        let (g, missing) = import_lenient(&raw, &al, registry).map_err(FileError::at(input))?;
        for w in crate::f3d::warnings(&g) {
            eprintln!("warning: {}: {w}", input.display());
        }
        if !missing.is_empty() {
            eprintln!(
                "warning: {}: the graph was converted, but it will not run until these exist: {}",
                input.display(),
                missing.join(", ")
            );
        }
        let text = serde_json::to_string_pretty(&g)?;
        crate::io::write_atomic(output, |w| w.write_all(text.as_bytes()))
            .map_err(FileError::at(output))?;
        Ok(())
    })();
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_INVALID
        }
    }
}

/// `cgnodes import-f3d --list-map [--markdown] [--f3d-aliases FILE]`: prints every node map.
pub(super) fn list_map(aliases: Option<&Path>, markdown: bool) -> i32 {
    let result = (|| -> Result<String, ImportF3dError> {
        let al = aliases.map(read_aliases).transpose()?.unwrap_or_default();
        let maps = crate::f3d::node_maps(&al)?;
        Ok(crate::f3d::table::map_table(&maps, markdown))
    })();
    match result {
        Ok(t) => {
            print!("{t}");
            0
        }
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_INVALID
        }
    }
}
