//! Mesh I/O against the course and literature meshes shipped in `assets/`, round trips, and
//! every bad-input case of issue 3.

use cgnodes::nodes::mesh::load::{load_mesh, LoadOptions};
use cgnodes::nodes::mesh::{obj, ply, usda};
use cgnodes::types::{Attribute, Domain, Mesh};
use std::path::{Path, PathBuf};

fn asset(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

fn opts() -> LoadOptions {
    LoadOptions {
        apply_transform: true,
        ..Default::default()
    }
}

fn load(p: &str) -> Mesh {
    load_mesh(&asset(p), &opts()).unwrap_or_else(|e| panic!("{e}"))
}

/// Vertex and face counts from `shared/reference/framework3d/FORMAT.md`; the hw8 grids are
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
    let e = load_mesh(&asset("assets/course/Balls.usda"), &o).unwrap_err();
    assert!(
        e.contains("not a Mesh") && e.contains("/Balls/Balls"),
        "{e}"
    );
    // arm: skinning weights come through as a vertex attribute
    let arm = load("assets/course/arm.usda");
    assert!(arm.attributes.contains_key("skel:jointWeights"));
}
