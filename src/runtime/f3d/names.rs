//! Where Framework3D's Write USD nodes write: file names under the output folder.

use super::{F3dNode, F3dSocket};
use std::collections::BTreeMap;

/// A prim path as part of a file name: letters, digits, `-` and `_` kept, the rest `_`.
fn file_part(prim: &str) -> String {
    prim.trim_matches('/')
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The file each Write USD node writes: its `File Name` under the output folder; with the
/// prim name added when several Write USD nodes share that file (Framework3D writes them as
/// prims of one stage), and `_{frame:04}` when its Time Code is linked (one file per frame).
pub(super) fn write_usd_paths(
    nodes: &[F3dNode],
    sockets: &BTreeMap<i64, F3dSocket>,
    linked: &dyn Fn(i64) -> bool,
) -> BTreeMap<i64, String> {
    let widget = |n: &F3dNode, ident: &str| {
        n.inputs
            .iter()
            .find(|s| sockets.get(s).is_some_and(|s| s.identifier == ident))
            .copied()
    };
    let text = |s: Option<i64>, default: &str| {
        s.and_then(|s| sockets.get(&s))
            .and_then(|s| s.value.as_ref())
            .and_then(|v| v.as_str())
            .unwrap_or(default)
            .to_string()
    };
    let writers: Vec<(i64, String, String, bool)> = nodes
        .iter()
        .filter(|n| n.id_name == "geom_write_usd")
        .map(|n| {
            let file = write_usd_path(&text(widget(n, "File Name"), "Default"));
            let prim = text(widget(n, "Prim Path"), "geometry");
            let timed = widget(n, "Time Code").is_some_and(linked);
            (n.id, file, prim, timed)
        })
        .collect();
    writers
        .iter()
        .map(|(id, file, prim, timed)| {
            let shared = writers.iter().filter(|w| &w.1 == file).count() > 1;
            let (stem, ext) = file.rsplit_once('.').unwrap_or((file.as_str(), "usda"));
            let mut name = stem.to_string();
            if shared {
                name.push('_');
                name.push_str(&file_part(prim));
            }
            if *timed {
                name.push_str("_{frame:04}");
            }
            (*id, format!("{name}.{ext}"))
        })
        .collect()
}

/// Framework3D's `File Name` of Write USD as a path under the output directory: the file
/// name only, with `.usda` added when it has no mesh extension.
pub(super) fn write_usd_path(p: &str) -> String {
    let name = std::path::Path::new(p)
        .file_name()
        .and_then(|s| s.to_str())
        .unwrap_or("output")
        .to_string();
    let lower = name.to_ascii_lowercase();
    if [".usda", ".usd", ".obj", ".ply", ".off"]
        .iter()
        .any(|e| lower.ends_with(e))
    {
        name
    } else {
        format!("{name}.usda")
    }
}
