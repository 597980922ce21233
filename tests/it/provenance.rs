//! Provenance round trips (issue 30): a real graph writes every format, and the record read
//! back from each file (embedded, or its sidecar) names the node, its type, its literal
//! parameters, the frame and the hash of the graph text; each file still reads back as its
//! format (the record does not corrupt it).

use crate::common::{asset, run_graph};
use cgnodes::exec::NodeStatus;
use cgnodes::node::Provenance;
use cgnodes::types::Value;
use serde_json::json;
use std::path::Path;

const GRAPH: &str = r#"{
  "format": "cgnodes-graph", "version": 1,
  "nodes": {
    "grid": {"type": "mesh_grid", "params": {"cells_u": 3, "cells_v": 2}},
    "obj": {"type": "mesh_save", "params": {"path": "m{frame}.obj"}, "inputs": {"mesh": "grid.mesh"}},
    "ply": {"type": "mesh_save", "params": {"path": "m.ply"}, "inputs": {"mesh": "grid.mesh"}},
    "plyb": {"type": "mesh_save", "params": {"path": "mb.ply", "binary": true}, "inputs": {"mesh": "grid.mesh"}},
    "usda": {"type": "mesh_save", "params": {"path": "m.usda"}, "inputs": {"mesh": "grid.mesh"}},
    "off": {"type": "mesh_save", "params": {"path": "m.off"}, "inputs": {"mesh": "grid.mesh"}},
    "img": {"type": "image_load", "params": {"path": "IMAGE"}},
    "png": {"type": "image_save", "params": {"path": "i.png", "exposure": 0.5}, "inputs": {"image": "img.image"}},
    "exr": {"type": "image_save", "params": {"path": "i.exr"}, "inputs": {"image": "img.image"}},
    "hdr": {"type": "image_save", "params": {"path": "i.hdr"}, "inputs": {"image": "img.image"}},
    "info": {"type": "mesh_info", "inputs": {"mesh": "grid.mesh"}},
    "csv": {"type": "table_write", "params": {"path": "t.csv"}, "inputs": {"value": "info.table"}},
    "svg": {"type": "plot", "params": {"path": "p.svg", "series_1": [[0, 0], [1, 2]], "title": "a -- b"}},
    "plotpng": {"type": "plot", "params": {"path": "p.png", "series_1": [[0, 0], [1, 2]], "width": 200, "height": 150}}
  }
}"#;

fn graph_text() -> String {
    let img = asset("assets/images/lena_gray128.png");
    GRAPH.replace("IMAGE", &img.display().to_string())
}

/// Runs the graph at frame 3 into `out` and returns its text.
fn write_all(out: &Path) -> String {
    let text = graph_text();
    let reg = cgnodes::nodes::builtin_registry();
    let r = run_graph(&text, &reg, out, out, 1, 3..=3);
    for n in &r[0].nodes {
        assert!(
            !matches!(n.status, NodeStatus::Failed(_) | NodeStatus::Blocked { .. }),
            "{}: {:?}",
            n.id,
            n.status
        );
    }
    text
}

fn check(out: &Path, file: &str, node: &str, node_type: &str, text: &str) -> Provenance {
    let p = Provenance::read(&out.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
    assert_eq!(p.node, node, "{file}");
    assert_eq!(p.node_type, node_type, "{file}");
    assert_eq!(p.frame, 3, "{file}");
    assert_eq!(p.cgnodes, env!("CARGO_PKG_VERSION"));
    assert_eq!(
        p.graph_hash,
        format!("blake3:{}", blake3::hash(text.as_bytes()).to_hex()),
        "{file}"
    );
    p
}

#[test]
fn every_written_format_records_node_params_frame_and_graph_hash() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path();
    let text = write_all(out);
    // Embedded in the file.
    let p = check(out, "m3.obj", "obj", "mesh_save", &text);
    assert_eq!(p.params.get("path"), Some(&json!("m{frame}.obj")));
    check(out, "m.ply", "ply", "mesh_save", &text);
    let p = check(out, "mb.ply", "plyb", "mesh_save", &text);
    assert_eq!(p.params.get("binary"), Some(&json!(true)));
    check(out, "m.usda", "usda", "mesh_save", &text);
    let p = check(out, "i.png", "png", "image_save", &text);
    assert_eq!(p.params.get("exposure"), Some(&json!(0.5)));
    // Defaults are not parameters of the graph.
    assert!(!p.params.contains_key("gamma"));
    check(out, "i.exr", "exr", "image_save", &text);
    let p = check(out, "p.svg", "svg", "plot", &text);
    assert_eq!(p.params.get("title"), Some(&json!("a -- b")));
    check(out, "p.png", "plotpng", "plot", &text);
    // Sidecars: CSV, OFF, HDR.
    for (file, node, ty) in [
        ("t.csv", "csv", "table_write"),
        ("m.off", "off", "mesh_save"),
        ("i.hdr", "hdr", "image_save"),
    ] {
        assert!(
            out.join(format!("{file}.provenance.json")).exists(),
            "{file}"
        );
        check(out, file, node, ty, &text);
    }
    // The PNG's record is a standard tEXt chunk with keyword `cgnodes`.
    let png = std::fs::read(out.join("i.png")).unwrap();
    assert!(png.windows(12).any(|w| w == b"tEXtcgnodes\0"));
}

#[test]
fn files_with_a_record_still_read_as_their_format() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path();
    write_all(out);
    // Images decode, with the pixels of the input (EXR: linear float; image_load decodes the
    // sRGB PNG to linear).
    let src = image::open(asset("assets/images/lena_gray128.png"))
        .unwrap()
        .to_rgba32f();
    let exr = image::open(out.join("i.exr")).unwrap().to_rgba32f();
    assert_eq!(exr.dimensions(), src.dimensions());
    let max_diff = exr
        .pixels()
        .zip(src.pixels())
        .map(|(a, b)| (a.0[0] - srgb_to_linear(b.0[0])).abs())
        .fold(0.0f32, f32::max);
    assert!(max_diff < 1e-3, "EXR pixels differ by {max_diff}");
    let png = image::open(out.join("i.png")).unwrap();
    assert_eq!(png.width(), 128);
    let plot = image::open(out.join("p.png")).unwrap();
    assert_eq!((plot.width(), plot.height()), (200, 150));
    // Meshes load back with the grid's 12 vertices and 12 triangles.
    for f in ["m3.obj", "m.ply", "mb.ply", "m.usda"] {
        let (o, _) = crate::common::run_node(
            "mesh_load",
            vec![("path", Value::String(out.join(f).display().to_string()))],
            &Default::default(),
        )
        .unwrap_or_else(|e| panic!("{f}: {e}"));
        let Some(Value::Mesh(m)) = o.get("mesh") else {
            panic!("{f}: no mesh")
        };
        assert_eq!((m.positions.len(), m.num_faces()), (12, 12), "{f}");
    }
    // The CSV itself is unchanged: a header row and one row of numbers.
    let csv = std::fs::read_to_string(out.join("t.csv")).unwrap();
    assert_eq!(csv.lines().count(), 2, "{csv}");
}

#[test]
fn cli_prints_the_record_as_json_and_text() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path();
    write_all(out);
    let bin = env!("CARGO_BIN_EXE_cgnodes");
    let o = std::process::Command::new(bin)
        .args(["provenance", "--json"])
        .arg(out.join("mb.ply"))
        .output()
        .unwrap();
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["node"], "plyb");
    assert_eq!(v["params"]["path"], "mb.ply");
    let o = std::process::Command::new(bin)
        .arg("provenance")
        .arg(out.join("t.csv"))
        .output()
        .unwrap();
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success() && s.contains("node:       csv (table_write)"),
        "{s}"
    );
    // A file with no record is an error naming it.
    std::fs::write(out.join("plain.txt"), "x").unwrap();
    let o = std::process::Command::new(bin)
        .arg("provenance")
        .arg(out.join("plain.txt"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("plain.txt"));
}

/// The sRGB transfer function's inverse (IEC 61966-2-1).
fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}
