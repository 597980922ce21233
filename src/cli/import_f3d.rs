//! `cgnodes import-f3d`: converts a Framework3D saved node tree into a cgnodes graph file.

use super::validate::read_aliases;
use super::EXIT_INVALID;
use crate::f3d::import_lenient;
use crate::registry::Registry;
use std::path::Path;

/// `cgnodes import-f3d INPUT -o OUTPUT [--f3d-aliases FILE]`. Nodes missing from
/// `registry` (built-in and plugin nodes) are reported but do not stop the conversion.
pub(super) fn cmd(registry: &Registry, input: &Path, output: &Path, aliases: Option<&Path>) -> i32 {
    let read_json = |p: &Path| -> Result<serde_json::Value, String> {
        let t = std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()))?;
        crate::io::json::parse_strict(&t).map_err(|e| format!("{}: {e}", p.display()))
    };
    let result = (|| -> Result<(), String> {
        let raw = read_json(input)?;
        let al = aliases.map(read_aliases).transpose()?.unwrap_or_default();
        let (g, missing) =
            import_lenient(&raw, &al, registry).map_err(|e| format!("{}: {e}", input.display()))?;
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
        let text = serde_json::to_string_pretty(&g).map_err(|e| e.to_string())?;
        crate::io::write_atomic(output, |w| w.write_all(text.as_bytes()))
            .map_err(|e| format!("{}: {e}", output.display()))
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
    let result = (|| -> Result<String, String> {
        let al = aliases.map(read_aliases).transpose()?.unwrap_or_default();
        let maps = crate::f3d::node_maps(&al).map_err(|e| e.to_string())?;
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
