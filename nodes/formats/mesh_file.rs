//! Mesh files in: OBJ, text USD (`.usda`), PLY (ASCII or binary) and OFF, chosen by the
//! file's extension.

use cgnodes_api::prelude::*;
use std::path::Path;

/// What `load_mesh` should pick out of a file.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// USD prim path (`/Balls/Balls`); empty: the first Mesh.
    pub prim: String,
    /// OBJ group or object name; empty: all groups merged.
    pub group: String,
    /// Apply USD `xformOp`s of the prim and its ancestors.
    pub apply_transform: bool,
}

/// Reads a mesh file, choosing the format by extension (`obj`, `usda`/`usd`, `ply`, `off`).
/// Errors name the file and, for text formats, the offending line.
pub fn load_mesh(path: &Path, opts: &LoadOptions) -> Result<Mesh, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let name = path.display();
    if !path.exists() {
        return Err(format!("{name}: file not found"));
    }
    let read_text =
        || std::fs::read_to_string(path).map_err(|e| format!("{name}: cannot read: {e}"));
    let r = match ext.as_str() {
        "obj" => super::obj::load_obj(path, &opts.group),
        "usda" | "usd" => {
            let text = read_text()?;
            super::usda::read_usda(&text, &opts.prim, opts.apply_transform)
        }
        "ply" => {
            let bytes = std::fs::read(path).map_err(|e| format!("{name}: cannot read: {e}"))?;
            super::ply::read_ply(&bytes)
        }
        "off" => super::off::read_off(&read_text()?),
        other => {
            return Err(format!(
                "{name}: unknown mesh format '.{other}' (obj, usda, ply, off are read)"
            ))
        }
    };
    r.map_err(|e| format!("{name}: {e}"))
}
