//! Entry points of the fuzz targets (`fuzz/`): one function per reader of untrusted bytes,
//! feeding `data` through it the way a run would. The fuzz targets call these, and so does the
//! regression test that replays every crashing input found (`tests/it/hostile.rs`), so the two
//! cannot drift apart. None may panic, whatever `data` holds; errors are expected and ignored.

use crate::types::SocketType;
use std::path::Path;

/// Splits `data` at its first NUL byte (two inputs in one), or gives `data` and `rest`.
fn split<'a>(data: &'a [u8], rest: &'a [u8]) -> (&'a [u8], &'a [u8]) {
    match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, rest),
    }
}

/// Native graph JSON: parse, validate against the built-in nodes, render as DOT.
pub fn graph_json(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let reg = crate::nodes::builtin_registry();
    if let Ok(g) = crate::graph::parse(text, Path::new("fuzz.json"), Path::new("/nonexistent")) {
        if let Ok(v) = crate::validate::validate(&g, &reg) {
            let _ = v.to_dot();
        }
    }
}

/// Framework3D node trees (before the first NUL byte) with aliases (after it): strict and
/// lenient import, then parse and validate as a graph.
pub fn graph_f3d(data: &[u8]) {
    let (tree, aliases) = split(data, b"{}");
    let Ok(raw) = serde_json::from_slice::<serde_json::Value>(tree) else {
        return;
    };
    let aliases: crate::f3d::Aliases = serde_json::from_slice(aliases).unwrap_or_default();
    let reg = crate::nodes::builtin_registry();
    let _ = crate::f3d::import(&raw, &aliases, &reg);
    let _ = crate::f3d::import_lenient(&raw, &aliases, &reg);
    let text = String::from_utf8_lossy(tree);
    let (file, dir) = (Path::new("fuzz.json"), Path::new("/nonexistent"));
    if let Ok(g) = crate::graph::parse_with(&text, file, dir, &aliases, &reg) {
        let _ = crate::validate::validate(&g, &reg);
    }
}

/// OBJ, written to `scratch`: merged, one group, and per object.
pub fn obj(data: &[u8], scratch: &Path) {
    use cgnodes_formats::obj;
    let p = scratch.join("in.obj");
    if std::fs::write(&p, data).is_err() {
        return;
    }
    let _ = obj::load_obj(&p, "");
    let _ = obj::load_obj(&p, "g0");
    let _ = obj::load_obj_objects(&p);
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = obj::find_bad_obj_line(text);
    }
}

/// An MTL library (written to `scratch`) named by a fixed textured triangle.
pub fn mtl(data: &[u8], scratch: &Path) {
    const OBJ: &str = "mtllib in.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
                       usemtl m\nf 1/1 2/2 3/3\n";
    let p = scratch.join("mtl.obj");
    if std::fs::write(scratch.join("in.mtl"), data).is_err() || std::fs::write(&p, OBJ).is_err() {
        return;
    }
    let _ = cgnodes_formats::obj::load_obj_objects(&p);
}

/// Image file bytes (PNG, JPEG, EXR, HDR, BMP, GIF): the structural check and the decoder,
/// in both colour spaces.
pub fn image(data: &[u8]) {
    use cgnodes_formats::image_file::{decode_image, ColorSpace};
    let _ = decode_image(data, ColorSpace::Srgb);
    let _ = decode_image(data, ColorSpace::Raw);
}

/// OFF text.
pub fn off(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = cgnodes_formats::off::read_off(text);
    }
}

/// PLY, ASCII and binary.
pub fn ply(data: &[u8]) {
    let _ = cgnodes_formats::ply::read_ply(data);
}

/// USDA: the layer parser, then the first mesh prims, with and without transforms.
pub fn usda(data: &[u8]) {
    use cgnodes_formats::usda;
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(layer) = usda::parse_usda(text) else {
        return;
    };
    let _ = usda::read_usda(text, "", true);
    for p in usda::mesh_paths(&layer).iter().take(4) {
        let _ = usda::read_usda(text, p, true);
        let _ = usda::read_usda(text, p, false);
    }
}

/// `.npy` arrays and their conversions.
pub fn npy(data: &[u8]) {
    if let Ok(a) = crate::plugin::npy::NpyArray::from_bytes(data) {
        let _ = a.shape_str();
        let _ = a.to_f64();
        let _ = a.to_i64();
        let _ = a.to_bytes();
    }
}

/// CSV: the shared reader with every option, and `compare_series`' column reader.
pub fn csv(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    for comments in [false, true] {
        for trim in [false, true] {
            let _ = crate::io::csv::read(text, comments, trim);
        }
    }
    #[cfg(feature = "metrics")]
    {
        use crate::nodes::metrics::compare_series::read_csv_columns;
        let _ = read_csv_columns(text, "x", "y");
        let _ = read_csv_columns(text, "T", "Z");
    }
}

/// A plugin manifest (written to `scratch/plugin/`), loaded and registered.
pub fn plugin_manifest(data: &[u8], scratch: &Path) {
    let dir = scratch.join("plugin");
    if std::fs::create_dir_all(&dir).is_err()
        || std::fs::write(dir.join(crate::plugin::MANIFEST), data).is_err()
    {
        return;
    }
    if let Ok(p) = crate::plugin::load(&dir) {
        let mut reg = crate::nodes::builtin_registry();
        let _ = crate::plugin::register(&mut reg, p);
    }
}

/// A plugin reply: JSON (before the first NUL byte) decoded as each socket type, with the
/// bytes after it as the `.npy` file `a.npy` the reply may name (in `scratch/call/`).
pub fn plugin_reply(data: &[u8], scratch: &Path) {
    let (json, npy) = split(data, &[]);
    let Ok(j) = serde_json::from_slice::<serde_json::Value>(json) else {
        return;
    };
    let dir = scratch.join("call");
    if std::fs::create_dir_all(&dir).is_err() || std::fs::write(dir.join("a.npy"), npy).is_err() {
        return;
    }
    let inputs = Default::default();
    for ty in [
        SocketType::Mesh,
        SocketType::Points,
        SocketType::Image,
        SocketType::Table,
        SocketType::Curve,
        SocketType::Float,
        SocketType::Int,
        SocketType::Vec3,
        SocketType::String,
        SocketType::List(Box::new(SocketType::Float)),
        SocketType::List(Box::new(SocketType::Mesh)),
    ] {
        let _ = crate::plugin::codec::decode(&ty, &j, &dir, &inputs);
    }
}

/// Runs the entry point of fuzz target `target` on `data` (`scratch` for path-based readers);
/// false for an unknown target.
pub fn run(target: &str, data: &[u8], scratch: &Path) -> bool {
    match target {
        "graph_json" => graph_json(data),
        "graph_f3d" => graph_f3d(data),
        "obj" => obj(data, scratch),
        "mtl" => mtl(data, scratch),
        "off" => off(data),
        "image" => image(data),
        "ply" => ply(data),
        "usda" => usda(data),
        "npy" => npy(data),
        "csv" => csv(data),
        "plugin_manifest" => plugin_manifest(data, scratch),
        "plugin_reply" => plugin_reply(data, scratch),
        _ => return false,
    }
    true
}
