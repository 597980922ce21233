//! Mesh I/O against the course and literature meshes shipped in `assets/`, round trips, and
//! every bad-input case of issue 3.

use cgnodes::nodes::mesh::mesh_load::{load_mesh, LoadOptions};
use cgnodes::nodes::mesh::{obj, ply, usda};
use cgnodes::types::{Attribute, Domain, Mesh};
use std::path::{Path, PathBuf};

use crate::common::asset;

fn opts() -> LoadOptions {
    LoadOptions {
        apply_transform: true,
        ..Default::default()
    }
}

fn load(p: &str) -> Mesh {
    load_mesh(&asset(p), &opts()).unwrap_or_else(|e| panic!("{e}"))
}

/// Vertex and face counts from the Framework3D format notes of the course; the hw8 grids are
/// n x n squares split in two triangles ((n+1)^2 vertices, 2 n^2 faces); the sphere is a
/// 3-times subdivided icosahedron (642 vertices, 1280 faces); `arm.usda` is hand-written
/// with 12 points and 10 quads.
#[test]
fn all_course_usda_meshes_load_with_their_sizes() {
    let want = [
        ("Balls", 547, 1032),
        ("BunnyHead", 741, 1448),
        ("CatHead", 135, 257),
        ("David328", 315, 586),
        ("NefertitiFace", 299, 562),
        ("Beetle_ABF", 984, 1759),
        ("Cow_dABF", 3195, 5804),
        ("Gargoyle_ABF", 10229, 20000),
        ("Isis_dABF", 458, 879),
        ("grid10x10", 121, 200),
        ("grid20x20", 441, 800),
        ("grid40x40", 1681, 3200),
        ("sphere", 642, 1280),
        ("arm", 12, 10),
    ];
    for (name, nv, nf) in want {
        let m = load(&format!("assets/course/{name}.usda"));
        assert_eq!((m.num_vertices(), m.num_faces()), (nv, nf), "{name}");
        m.check().unwrap();
    }
}

#[test]
fn usda_uvs_normals_and_transform() {
    // hw8 grid: faceVarying UVs, one per corner, on [0,1]^2 matching the grid's x, y in [-1,1].
    let g = load("assets/course/grid10x10.usda");
    let uv = g.uvs.as_ref().unwrap();
    assert_eq!(uv.domain, Domain::Corner);
    assert_eq!(uv.values.len(), 600);
    for (c, &v) in g.face_indices().iter().enumerate() {
        let p = g.positions[v as usize];
        let t = uv.values[c];
        assert!((t[0] - (p[0] + 1.0) / 2.0).abs() < 1e-6, "{t:?} {p:?}");
        assert!((t[1] - (p[1] + 1.0) / 2.0).abs() < 1e-6, "{t:?} {p:?}");
    }
    assert_eq!(g.normals.as_ref().unwrap().domain, Domain::Corner);
    // Balls: the Xform turns the file's (x, y, z) into (x, -z, y) (a +90 degree turn about
    // x); its points have extent z in [-3, 3], so after the transform y spans [-3, 3].
    let b = load("assets/course/Balls.usda");
    let (lo, hi) = b.bounds();
    assert!(
        (lo[1] + 3.0).abs() < 1e-5 && (hi[1] - 3.0).abs() < 1e-5,
        "{lo:?} {hi:?}"
    );
    let raw = load_mesh(&asset("assets/course/Balls.usda"), &LoadOptions::default()).unwrap();
    let (lo, hi) = raw.bounds();
    assert!((lo[2] + 3.0).abs() < 1e-9 && (hi[2] - 3.0).abs() < 1e-9);
    // prim selection by path, with and without the leading slash
    let o = LoadOptions {
        prim: "Balls/Balls".into(),
        ..opts()
    };
    assert_eq!(
        load_mesh(&asset("assets/course/Balls.usda"), &o)
            .unwrap()
            .num_vertices(),
        547
    );
    let o = LoadOptions {
        prim: "/_materials".into(),
        ..opts()
    };
    let e = load_mesh(&asset("assets/course/Balls.usda"), &o)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("not a Mesh") && e.contains("/Balls/Balls"),
        "{e}"
    );
    // arm: the skinning weights come through as the mesh's skeleton binding, one set of
    // influences per vertex
    let arm = load("assets/course/arm.usda");
    let skin = arm.skin.as_ref().expect("arm.usda is bound to a skeleton");
    assert_eq!(skin.num_vertices(), arm.num_vertices());
    assert_eq!(skin.joint_weights.len(), skin.joint_indices.len());
}

#[test]
fn literature_obj_meshes_load() {
    // Vertex and face counts of the shipped files (`grep -c '^v '`, `grep -c '^f '`); the
    // face counts are the ones assets/README.md gives (3.6k, 22.7k, 44k).
    for (name, nv, nf) in [
        ("camel_b", 2032, 3576),
        ("camelhead", 11381, 22704),
        ("bunny_closed", 3485, 6966),
        ("beetle_11holes", 19887, 38656),
        ("nefertiti_front", 22488, 44416),
    ] {
        let path = format!("assets/meshes/{name}.obj");
        let m = load(&path);
        // Count `v` and `f` lines independently of tobj.
        let text = std::fs::read_to_string(asset(&path)).unwrap();
        let v = text.lines().filter(|l| l.starts_with("v ")).count();
        let f = text.lines().filter(|l| l.starts_with("f ")).count();
        assert_eq!((v, f), (nv, nf), "{name}: the file changed");
        assert_eq!((m.num_vertices(), m.num_faces()), (nv, nf), "{name}");
    }
    // beetle_11holes: genus 0 with 11 boundary loops (assets/README.md), so chi = 2 - 11
    let b = load("assets/meshes/beetle_11holes.obj");
    assert_eq!(b.topology().boundary_loops.len(), 11);
    assert_eq!(b.topology().euler_characteristic(), -9);
    assert_eq!(
        load("assets/meshes/bunny_closed.obj").topology().genus(),
        Some(0)
    );
}

/// A mesh with values that f32 cannot hold, a quad, and per-corner UVs.
fn sample() -> Mesh {
    let p = vec![
        [0.1, 0.2, 0.3],
        [1.0 / 3.0, 0.0, -1e-17],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 2.5e10],
        [0.5, 0.5, std::f64::consts::PI],
    ];
    let mut m = Mesh::new(p, vec![4, 3], vec![0, 1, 2, 3, 1, 4, 2]).unwrap();
    m.uvs = Some(Attribute {
        domain: Domain::Corner,
        values: (0..7)
            .map(|i| [i as f64 / 7.0, 1.0 - i as f64 / 9.0])
            .collect(),
    });
    m
}

fn tmp(name: &str) -> (tempfile::TempDir, PathBuf) {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join(name);
    (d, p)
}

#[test]
fn obj_usda_ply_round_trips_are_exact() {
    let m = sample();
    let check = |r: &Mesh, what: &str| {
        assert_eq!(r.positions, m.positions, "{what}");
        assert_eq!(r.face_counts(), m.face_counts(), "{what}");
        assert_eq!(r.face_indices(), m.face_indices(), "{what}");
        assert_eq!(r.uvs, m.uvs, "{what}");
    };
    let (_d, p) = tmp("a.obj");
    let mut f = std::fs::File::create(&p).unwrap();
    obj::write_obj(&m, None, &mut f).unwrap();
    drop(f);
    check(&load_mesh(&p, &opts()).unwrap(), "obj");
    let (_d2, p) = tmp("a.usda");
    let mut f = std::fs::File::create(&p).unwrap();
    usda::write_usda(&m, "/root/thing", &mut f).unwrap();
    drop(f);
    check(&load_mesh(&p, &opts()).unwrap(), "usda");
    for binary in [false, true] {
        let (_d3, p) = tmp("a.ply");
        let mut f = std::fs::File::create(&p).unwrap();
        ply::write_ply(&m, binary, &mut f).unwrap();
        drop(f);
        check(&load_mesh(&p, &opts()).unwrap(), "ply");
    }
    // A course mesh through USDA: what was read is what is read back.
    let g = load("assets/course/grid10x10.usda");
    let (_d4, p) = tmp("g.usda");
    let mut f = std::fs::File::create(&p).unwrap();
    usda::write_usda(&g, "/Grid/Grid", &mut f).unwrap();
    drop(f);
    let r = load_mesh(&p, &opts()).unwrap();
    assert_eq!(r.positions, g.positions);
    assert_eq!(r.uvs, g.uvs);
    assert_eq!(r.normals, g.normals);
}

#[test]
fn obj_groups_merge_or_select() {
    let p = asset("tests/data/mesh/two_groups.obj");
    let m = load_mesh(&p, &opts()).unwrap();
    // merged: the shared edge 2-3 keeps one copy of its vertices
    assert_eq!((m.num_vertices(), m.num_faces()), (4, 2));
    assert_eq!(m.topology().boundary_loops.len(), 1);
    assert_eq!(m.uvs.as_ref().unwrap().values[3], [1.0, 0.0]);
    let o = LoadOptions {
        group: "right".into(),
        ..opts()
    };
    let r = load_mesh(&p, &o).unwrap();
    assert_eq!((r.num_vertices(), r.num_faces()), (3, 1));
    let o = LoadOptions {
        group: "middle".into(),
        ..opts()
    };
    let e = load_mesh(&p, &o).unwrap_err().to_string();
    assert!(e.contains("left") && e.contains("right"), "{e}");
}

fn load_err(p: &str) -> String {
    load_mesh(&asset(p), &opts()).unwrap_err().to_string()
}

#[test]
fn bad_inputs_give_clear_errors() {
    let e = load_err("tests/data/mesh/does_not_exist.obj");
    assert!(e.contains("not found"), "{e}");
    let e = load_err("tests/data/mesh/malformed.obj");
    assert!(e.contains("line 4") && e.contains("oops"), "{e}");
    let e = load_err("tests/data/mesh/nan.obj");
    assert!(e.contains("line 3") && e.contains("finite"), "{e}");
    let e = load_err("tests/data/mesh/index_out_of_range.obj");
    assert!(e.contains("line 5") && e.contains("out of range"), "{e}");
    let e = load_err("tests/data/mesh/degenerate.obj");
    assert!(e.contains("line 5") && e.contains("degenerate"), "{e}");
    let e = load_err("tests/data/mesh/inf.off");
    assert!(e.contains("line 5") && e.contains("finite"), "{e}");
    let e = load_err("tests/data/mesh/index_out_of_range.ply");
    assert!(e.contains("vertex 5"), "{e}");
    let e = load_err("tests/data/mesh/unsupported.usda");
    assert!(e.contains("line 11") && e.contains("variant"), "{e}");
    let (_d, p) = tmp("mesh.stl");
    std::fs::write(&p, "solid x").unwrap();
    let e = load_mesh(&p, &opts()).unwrap_err().to_string();
    assert!(e.contains("unknown mesh format"), "{e}");
}

#[test]
fn non_manifold_meshes_load_and_are_flagged() {
    let m = load("tests/data/mesh/nonmanifold.obj");
    let t = m.topology();
    assert!(!t.is_manifold());
    assert_eq!(t.nonmanifold_edges.len(), 1);
}

/// Runs one node outside a graph, its paths relative to the assets and `out`; its outputs.
fn run_node(
    name: &str,
    inputs: Vec<(&str, cgnodes::types::Value)>,
    out: &Path,
) -> Result<std::collections::BTreeMap<String, cgnodes::types::Value>, String> {
    let files = cgnodes::node::FileEnv {
        graph_dir: asset(""),
        out_dir: out.to_path_buf(),
        ..Default::default()
    };
    crate::common::run_node(name, inputs, &files).map(|(outputs, _)| outputs)
}

#[test]
fn obj_save_writes_mtl_and_texture_png() {
    use cgnodes::types::{Image, Material, Value};
    let dir = tempfile::tempdir().unwrap();
    let mut m = sample();
    let mut img = Image::new(2, 1, [0.0, 0.0, 0.0, 1.0]);
    img.set(1, 0, [1.0, 0.2158605, 0.0, 1.0]); // linear 0.21586 is sRGB 128/255 (IEC 61966-2-1)
    m.material = Some(std::sync::Arc::new(Material {
        name: "checker board".into(),
        base_color_texture: Some(std::sync::Arc::new(img)),
        ..Default::default()
    }));
    run_node(
        "mesh_save",
        vec![
            ("mesh", Value::from(m)),
            ("path", Value::from("tex/model.obj")),
        ],
        dir.path(),
    )
    .unwrap();
    let obj = std::fs::read_to_string(dir.path().join("tex/model.obj")).unwrap();
    assert!(obj.contains("mtllib model.mtl") && obj.contains("usemtl checker_board"));
    let mtl = std::fs::read_to_string(dir.path().join("tex/model.mtl")).unwrap();
    let tex = mtl
        .lines()
        .find_map(|l| l.strip_prefix("map_Kd "))
        .expect("map_Kd");
    let png = image::open(dir.path().join("tex").join(tex))
        .unwrap()
        .to_rgba8();
    assert_eq!(png.get_pixel(1, 0).0, [255, 128, 0, 255]);
    // tobj reads the pair back: the MTL names the texture, the faces keep their UVs
    let (_, mats) = tobj::load_obj(
        dir.path().join("tex/model.obj"),
        &tobj::LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(mats.unwrap()[0].diffuse_texture.as_deref(), Some(tex));
    let r = load_mesh(&dir.path().join("tex/model.obj"), &opts()).unwrap();
    assert_eq!(r.uvs, sample().uvs);
}

#[test]
fn mesh_nodes_run_and_report() {
    use cgnodes::types::Value;
    let dir = tempfile::tempdir().unwrap();
    let o = run_node(
        "mesh_load",
        vec![("path", Value::from("assets/course/arm.usda"))],
        dir.path(),
    )
    .unwrap();
    let arm = o["mesh"].clone();
    let o = run_node("mesh_info", vec![("mesh", arm.clone())], dir.path()).unwrap();
    let Value::Table(t) = &o["table"] else {
        panic!()
    };
    // a closed box of 10 quads around 12 vertices: V - E + F = 12 - 20 + 10 = 2
    assert_eq!(t.column("edges").unwrap()[0], 20.0);
    assert_eq!(t.column("genus").unwrap()[0], 0.0);
    let o = run_node("mesh_triangulate", vec![("mesh", arm)], dir.path()).unwrap();
    let Value::Mesh(tm) = &o["mesh"] else {
        panic!()
    };
    assert_eq!(tm.num_faces(), 20);
    assert!(tm.is_triangle_mesh());
    let e = run_node(
        "mesh_load",
        vec![("path", Value::from("tests/data/mesh/nan.obj"))],
        dir.path(),
    )
    .unwrap_err();
    assert!(e.contains("line 3"), "{e}");
}
