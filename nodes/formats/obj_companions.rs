//! The files an OBJ pulls in besides itself (its MTL libraries and their texture maps), so a
//! cache key that stamps an OBJ also sees an edit of its materials.

use cgnodes_api::io::{is_regular_file, read_prefix};
use std::io::BufRead;
use std::path::{Path, PathBuf};

/// At most this many companion files are listed per OBJ.
pub const MAX_COMPANIONS: usize = 256;

/// Statements of an MTL file that name a texture (the file name is the last word, after
/// any options).
const MTL_MAPS: &[&str] = &[
    "map_ka", "map_kd", "map_ks", "map_ke", "map_ns", "map_d", "map_bump", "bump", "disp", "decal",
    "refl", "norm", "map_pr", "map_pm", "map_ps",
];

/// The companions of an OBJ file: the MTL libraries it names (`mtllib`, relative to the
/// OBJ's folder) and the texture maps each MTL names (`map_Kd`, `bump`, ..., relative to the
/// MTL's folder). Names are taken both whole (as tobj reads them) and word by word.
pub fn obj_companions(path: &Path) -> Vec<PathBuf> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut out = Vec::new();
    if !is_regular_file(path) {
        return out;
    }
    let Ok(f) = std::fs::File::open(path) else {
        return out;
    };
    // Streamed: an OBJ may be large, and only its `mtllib` lines matter.
    for line in std::io::BufReader::new(f).split(b'\n') {
        let Ok(line) = line else { break };
        let line = String::from_utf8_lossy(&line);
        let Some(rest) = line.trim_start().strip_prefix("mtllib") else {
            continue;
        };
        if !rest.starts_with(char::is_whitespace) {
            continue;
        }
        for name in names(rest.trim()) {
            let mtl = dir.join(name);
            let textures = mtl_textures(&mtl);
            out.push(mtl);
            out.extend(textures);
            if out.len() >= MAX_COMPANIONS {
                return out;
            }
        }
    }
    out
}

/// The texture files an MTL file names.
fn mtl_textures(mtl: &Path) -> Vec<PathBuf> {
    let dir = mtl.parent().unwrap_or(Path::new("."));
    // MTL files are small; a larger one is read only as far as the stamp limit.
    let Some(bytes) = read_prefix(mtl, 256 * 1024) else {
        return Vec::new();
    };
    let text = String::from_utf8_lossy(&bytes);
    let mut out = Vec::new();
    for line in text.lines() {
        let mut words = line.split_whitespace();
        let Some(stmt) = words.next() else { continue };
        if !MTL_MAPS.contains(&stmt.to_ascii_lowercase().as_str()) {
            continue;
        }
        if let Some(file) = words.next_back() {
            out.push(dir.join(file));
        }
        if out.len() >= MAX_COMPANIONS {
            break;
        }
    }
    out
}

/// A file-name argument whole and, when it has several words, each word.
fn names(rest: &str) -> Vec<&str> {
    let mut v = vec![rest];
    if rest.contains(char::is_whitespace) {
        v.extend(rest.split_whitespace());
    }
    v
}
