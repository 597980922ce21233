//! Hostile mesh files through the graph runtime (issue 23): `mesh_load` on each fails with
//! an error naming the file's problem (no panic, abort or hang), and a 100k-corner polygon
//! loads and triangulates through the nodes. Unit tests in the readers cover the details.

use crate::common::run_graph;
use cgnodes::types::Value;

/// Runs `mesh_load` on `file` (written into a fresh folder as `name`) followed by
/// `mesh_triangulate` and a `mesh_save` (the sink that makes them run); returns the run report of frame 0.
fn load(name: &str, file: &[u8]) -> cgnodes::exec::RunReport {
    let d = tempfile::tempdir().unwrap();
    std::fs::write(d.path().join(name), file).unwrap();
    let g = format!(
        r#"{{"format": "cgnodes-graph", "version": 1, "nodes": {{
            "load": {{"type": "mesh_load", "params": {{"path": "{name}"}}}},
            "tri": {{"type": "mesh_triangulate", "inputs": {{"mesh": "load.mesh"}}}},
            "save": {{"type": "mesh_save", "params": {{"path": "t.off"}}, "inputs": {{"mesh": "tri.mesh"}}}}
        }}}}"#
    );
    let r = cgnodes::nodes::builtin_registry();
    let out = d.path().join("out");
    run_graph(&g, &r, d.path(), &out, 1, 0..=0).remove(0)
}

fn error_of(name: &str, file: &[u8]) -> String {
    let rep = load(name, file);
    assert!(!rep.ok(), "{name} loaded");
    rep.errors().join("\n")
}

#[test]
fn hostile_mesh_files_fail_with_clear_errors() {
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "huge.ply",
            b"ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec(),
            "element 'vertex' declares 1000000000000 instances, more than the 0 bytes",
        ),
        (
            "nan.ply",
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 nan 2\n".to_vec(),
            "face 0 refers to vertex NaN",
        ),
        (
            "counts.usda",
            b"#usda 1.0\ndef Mesh \"m\" {\n int[] faceVertexCounts = [9007199254740992, 9007199254740992]\n int[] faceVertexIndices = [0, 1, 2]\n point3f[] points = [(0,0,0), (1,0,0), (0,1,0)]\n}\n".to_vec(),
            "add up to more than the 3 entries",
        ),
        (
            "vt.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-9223372036854775807 2/1 3/1\n".to_vec(),
            "line 5: texture coordinate index -9223372036854775807 is out of range",
        ),
    ];
    for (name, bytes, want) in cases {
        let e = error_of(name, &bytes);
        assert!(
            e.contains("node 'load' (mesh_load)") && e.contains(want),
            "{name}: {e}"
        );
    }
}

/// A binary PLY with one 100k-corner polygon on a circle loads and triangulates into
/// n - 2 triangles (the O(n³) clipper and the O(k²) repeated-corner checks hung on it).
#[test]
fn a_100k_corner_face_loads_and_triangulates() {
    let n = 100_000u32;
    let mut b = format!("ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n").into_bytes();
    for k in 0..n {
        let a = std::f32::consts::TAU * k as f32 / n as f32;
        for v in [100.0 * a.cos(), 100.0 * a.sin(), 0.0] {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    b.extend_from_slice(&n.to_le_bytes());
    for k in 0..n as i32 {
        b.extend_from_slice(&k.to_le_bytes());
    }
    let rep = load("big.ply", &b);
    assert!(rep.ok(), "{:?}", rep.errors());
    let Some(Value::Mesh(m)) = rep.output("tri", "mesh") else {
        panic!("no mesh")
    };
    assert_eq!(m.num_faces(), n as usize - 2);
    assert!(m.is_triangle_mesh());
}
