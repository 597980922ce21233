//! Framework3D saved node trees: detection, import, aliases, missing-node reports, and a
//! graph of the homework's buffer nodes run end to end.

use cgnodes::exec::{Executor, RunOptions};
use cgnodes::f3d::{import, Aliases};
use cgnodes::node::FileEnv;
use cgnodes::nodes::builtin_registry;
use serde_json::{json, Value};
use std::path::Path;

use crate::common::root;

fn blueprint() -> Value {
    let t =
        std::fs::read_to_string(root().join("tests/data/f3d/hw4_tutte_blueprint.json")).unwrap();
    serde_json::from_str(&t).unwrap()
}

fn blueprint_aliases() -> Aliases {
    let t = std::fs::read_to_string(root().join("graphs/f3d/hw4_tutte_aliases.json")).unwrap();
    serde_json::from_str(&t).unwrap()
}

#[test]
fn blueprint_unknown_node_is_named_with_its_id() {
    assert!(cgnodes::f3d::is_f3d(&blueprint()));
    let e = import(&blueprint(), &Aliases::default(), &builtin_registry())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("geom_mesh_weight_shape_preserving (node 126)") && e.contains("--f3d-aliases"),
        "{e}"
    );
}

/// The conversions the importer must keep from the blueprint: ids, widget values and links.
fn check_blueprint_conversion(g: &cgnodes::graph::GraphFile) {
    assert_eq!(g.nodes["read_usd_1"].params["path"], json!("Balls.usda"));
    assert_eq!(g.nodes["read_usd_1"].params["prim"], json!("/Balls/Balls"));
    assert_eq!(
        g.nodes["write_usd_20"].params["path"],
        json!("Default.usda")
    );
    let link = |n: &str, s: &str| g.nodes[n].inputs[s].links()[0].to_string();
    assert_eq!(
        link("mesh_compose_57", "texcoords"),
        "buffer_compose2f_107.buffer"
    );
    assert_eq!(
        link("buffer_compose2f_107", "y"),
        "buffer_decompose3f_100.y"
    );
    assert_eq!(
        link("min_surf_14", "weights"),
        "mesh_weight_shape_preserving_126.value"
    );
    assert_eq!(
        link("set_texture_68", "image"),
        "set_texture_68_image_load.image"
    );
}

/// The nodes of the blueprint that need a node type of this build, with that type.
const BLUEPRINT_NEEDS: [(&str, &str); 4] = [
    ("geom_min_surf (node 14)", "tutte"),
    ("geom_set_texture (node 68)", "texture_map"),
    ("geom_set_texture (node 68)", "image_load"),
    ("geom_map_boundary_to_circle (node 131)", "boundary_map"),
];

/// With the alias file the blueprint converts with every node type of this build.
#[test]
fn blueprint_with_aliases_imports() {
    let reg = builtin_registry();
    for (node, ty) in BLUEPRINT_NEEDS {
        assert!(reg.get(ty).is_some(), "{node} needs '{ty}', not built in");
    }
    let g = import(&blueprint(), &blueprint_aliases(), &reg).unwrap();
    assert_eq!(g.nodes["min_surf_14"].node_type, "tutte");
    assert_eq!(g.nodes["read_usd_1"].node_type, "mesh_load");
    check_blueprint_conversion(&g);
}

/// Against a build that lacks some node types (the built-in registry without `tutte` and
/// `boundary_map`), the strict import names exactly the nodes that need them, and the lenient
/// import (import-f3d) still converts, keeping ids, links and widget values.
#[test]
fn blueprint_with_missing_node_types_is_named_or_converted_leniently() {
    let absent = ["tutte", "boundary_map"];
    let mut reg = cgnodes::registry::Registry::new();
    for d in builtin_registry().iter() {
        if !absent.contains(&d.type_name.as_str()) {
            reg.add_decl((**d).clone());
        }
    }
    let missing: Vec<_> = BLUEPRINT_NEEDS
        .iter()
        .filter(|(_, t)| absent.contains(t))
        .collect();
    assert_eq!(missing.len(), 2);
    let e = import(&blueprint(), &blueprint_aliases(), &reg)
        .unwrap_err()
        .to_string();
    for (node, ty) in &missing {
        assert!(e.contains(&format!("{node} needs '{ty}'")), "{e}");
    }
    let listed = e.matches(" needs '").count();
    assert_eq!(listed, missing.len(), "{e}");
    let (g, miss) = cgnodes::f3d::import_lenient(&blueprint(), &blueprint_aliases(), &reg).unwrap();
    assert_eq!(miss.len(), missing.len(), "{miss:?}");
    for (node, ty) in &missing {
        assert!(
            miss.iter().any(|m| m.contains(node) && m.contains(ty)),
            "{miss:?}"
        );
    }
    check_blueprint_conversion(&g);
}

/// A small Framework3D tree built here: nodes with numbered sockets, widget values, links.
struct Tree {
    next: i64,
    nodes: serde_json::Map<String, Value>,
    sockets: serde_json::Map<String, Value>,
    links: serde_json::Map<String, Value>,
}

impl Tree {
    fn new() -> Tree {
        Tree {
            next: 1,
            nodes: Default::default(),
            sockets: Default::default(),
            links: Default::default(),
        }
    }
    fn id(&mut self) -> i64 {
        self.next += 1;
        self.next
    }
    /// Adds a node; sockets are (identifier, kind, value). Returns (input ids, output ids).
    fn node(
        &mut self,
        name: &str,
        ins: &[(&str, &str, Value)],
        outs: &[(&str, &str)],
    ) -> (Vec<i64>, Vec<i64>) {
        let nid = self.id();
        let mut iv = Vec::new();
        let mut im = serde_json::Map::new();
        for (k, (ident, kind, val)) in ins.iter().enumerate() {
            let s = self.id();
            let mut sj = json!({"ID": s, "id_name": kind, "identifier": ident, "ui_name": ident, "in_out": 1});
            if !val.is_null() {
                sj["value"] = val.clone();
            }
            self.sockets.insert(s.to_string(), sj);
            im.insert(k.to_string(), json!(s));
            iv.push(s);
        }
        let mut ov = Vec::new();
        let mut om = serde_json::Map::new();
        for (k, (ident, kind)) in outs.iter().enumerate() {
            let s = self.id();
            self.sockets.insert(s.to_string(), json!({"ID": s, "id_name": kind, "identifier": ident, "ui_name": ident, "in_out": 0}));
            om.insert(k.to_string(), json!(s));
            ov.push(s);
        }
        self.nodes.insert(
            nid.to_string(),
            json!({"ID": nid, "id_name": name, "inputs": im, "outputs": om}),
        );
        (iv, ov)
    }
    fn link(&mut self, from: i64, to: i64) {
        let l = self.id();
        self.links.insert(
            l.to_string(),
            json!({"ID": l, "StartPinID": from, "EndPinID": to}),
        );
    }
    fn json(&self) -> Value {
        json!({"nodes_info": self.nodes, "sockets_info": self.sockets, "links_info": self.links, "nodes": {}, "selection": [], "view": {}})
    }
}

/// Read USD -> decompose -> X, Y of the vertices -> compose as texcoords -> Write USD:
/// the homework's "positions become UVs" pattern, with every node available in this build.
fn uv_from_xy_tree() -> Value {
    let mut t = Tree::new();
    let geo = "SocketGeometry";
    let (_, read) = t.node(
        "geom_read_usd",
        &[
            ("File Name", "SocketString", json!("grid10x10.usda")),
            ("Prim Path", "SocketString", json!("/Grid/Grid")),
            ("Time Code", "SocketFloat", json!(0)),
        ],
        &[("Geometry", geo)],
    );
    let f3 = "SocketFloat3Buffer";
    let i1 = "SocketInt1Buffer";
    let (dec_in, dec) = t.node(
        "geom_mesh_decompose",
        &[("Mesh", geo, Value::Null)],
        &[
            ("Vertices", f3),
            ("FaceVertexCounts", i1),
            ("FaceVertexIndices", i1),
            ("Normals", f3),
            ("Texcoords", "SocketFloat2Buffer"),
        ],
    );
    let f1 = "SocketFloat1Buffer";
    let (b3_in, b3) = t.node(
        "func_buffer_decompose3f",
        &[("Buffer", f3, Value::Null)],
        &[("X", f1), ("Y", f1), ("Z", f1), ("Size", "SocketInt")],
    );
    let (c2_in, c2) = t.node(
        "func_buffer_compose2f",
        &[("X", f1, Value::Null), ("Y", f1, Value::Null)],
        &[("Buffer", "SocketFloat2Buffer")],
    );
    let (comp_in, comp) = t.node(
        "geom_mesh_compose",
        &[
            ("Vertices", f3, Value::Null),
            ("FaceVertexCounts", i1, Value::Null),
            ("FaceVertexIndices", i1, Value::Null),
            ("Normals", f3, Value::Null),
            ("Texcoords", "SocketFloat2Buffer", Value::Null),
        ],
        &[("Mesh", geo)],
    );
    let (w_in, _) = t.node(
        "geom_write_usd",
        &[
            ("Geometry", geo, Value::Null),
            ("File Name", "SocketString", json!("C:/student/out/uv")),
            ("Prim Path", "SocketString", json!("geometry")),
            ("Time Code", "SocketFloat", json!(0)),
        ],
        &[],
    );
    let (_, tc) = t.node("geom_time_code", &[], &[("time", "SocketFloat")]);
    t.node(
        "geom_time_gain",
        &[("time", "SocketFloat", Value::Null)],
        &[],
    );
    t.link(read[0], dec_in[0]);
    t.link(dec[0], b3_in[0]);
    t.link(b3[0], c2_in[0]);
    t.link(b3[1], c2_in[1]);
    for k in 0..3 {
        t.link(dec[k], comp_in[k]);
    }
    t.link(c2[0], comp_in[4]);
    t.link(comp[0], w_in[0]);
    t.link(tc[0], w_in[3]); // a time code into a dropped socket
    t.json()
}

#[test]
fn buffer_pattern_runs_end_to_end() {
    let dir = tempfile::tempdir().unwrap();
    let gpath = dir.path().join("uv.json");
    std::fs::write(&gpath, serde_json::to_string(&uv_from_xy_tree()).unwrap()).unwrap();
    // `cgnodes run` path: graph::load recognises the tree.
    let g = cgnodes::graph::load_with(&gpath, &Aliases::default(), &builtin_registry()).unwrap();
    assert_eq!(g.spec.nodes.len(), 7, "{:?}", g.spec.nodes.keys());
    let reg = builtin_registry();
    let valid = cgnodes::validate::validate_with(&g, &reg, &[root().join("assets/course")])
        .unwrap_or_else(|e| panic!("{e:?}"));
    let out = dir.path().join("out");
    let opts = RunOptions {
        files: FileEnv {
            graph_dir: dir.path().to_path_buf(),
            asset_dirs: vec![root().join("assets/course")],
            out_dir: out.clone(),
            ..Default::default()
        },
        ..Default::default()
    };
    let r = Executor::new(Some(1), None).unwrap().run(&valid, &opts, 0);
    assert!(r.ok(), "{:?}", r.errors());
    // Write USD's File Name lands in the output directory, as USDA; its Time Code is linked,
    // so the frame number (0 in a single run) is part of the name.
    let written = out.join("uv_0000.usda");
    let m = cgnodes::nodes::mesh::mesh_load::load_mesh(
        &written,
        &cgnodes::nodes::mesh::mesh_load::LoadOptions {
            prim: "/geometry".into(),
            apply_transform: true,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!((m.num_vertices(), m.num_faces()), (121, 200));
    let uv = m.uvs.as_ref().unwrap();
    assert_eq!(uv.domain, cgnodes::types::Domain::Vertex);
    assert_eq!(uv.values.len(), m.positions.len());
    for (p, t) in m.positions.iter().zip(&uv.values) {
        assert_eq!([p[0], p[1]], *t);
    }
}

#[test]
fn bad_trees_give_clear_errors() {
    // a socket the map does not know, linked
    let mut v = uv_from_xy_tree();
    let sockets = v["sockets_info"].as_object_mut().unwrap();
    for s in sockets.values_mut() {
        if s["identifier"] == "Texcoords" && s["in_out"] == 1 {
            s["identifier"] = json!("UV");
        }
    }
    let e = import(&v, &Aliases::default(), &builtin_registry())
        .unwrap_err()
        .to_string();
    assert!(e.contains("geom_mesh_compose") && e.contains("'UV'"), "{e}");
    // storage feeding a real input
    let mut t = Tree::new();
    let (_, st) = t.node(
        "geom_storage_in",
        &[("Name", "SocketString", json!("m"))],
        &[("storage", "SocketGeometry")],
    );
    let (d, _) = t.node(
        "geom_mesh_decompose",
        &[("Mesh", "SocketGeometry", Value::Null)],
        &[],
    );
    t.link(st[0], d[0]);
    let e = import(&t.json(), &Aliases::default(), &builtin_registry())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("geom_storage_in") && e.contains("frame executor"),
        "{e}"
    );
    // a malformed alias
    let al: Aliases = serde_json::from_value(json!({"geom_x": {"typ": "a"}})).unwrap();
    let e = import(&t.json(), &al, &builtin_registry())
        .unwrap_err()
        .to_string();
    assert!(e.contains("alias for 'geom_x'"), "{e}");
    // a socket id that sockets_info does not list (issue 23: a panic while loading, exit 101)
    for drop_input in [true, false] {
        let mut v = uv_from_xy_tree();
        let linked_from: Vec<i64> = v["links_info"]
            .as_object()
            .unwrap()
            .values()
            .filter_map(|l| l["StartPinID"].as_i64())
            .collect();
        let sockets = v["sockets_info"].as_object_mut().unwrap();
        let key = sockets
            .iter()
            .find(|(_, s)| {
                let input = s["in_out"] == 1;
                input == drop_input && (input || linked_from.contains(&s["ID"].as_i64().unwrap()))
            })
            .map(|(k, _)| k.clone())
            .unwrap();
        sockets.remove(&key);
        let e = import(&v, &Aliases::default(), &builtin_registry())
            .unwrap_err()
            .to_string();
        assert!(e.contains("which sockets_info does not list"), "{e}");
    }
}

#[test]
fn socket_order_is_numeric_not_textual() {
    // Eleven inputs: keys "0".."10" are sorted "0","1","10","2" as text.
    let mut t = Tree::new();
    let ins: Vec<(String, &str, Value)> = (0..11)
        .map(|k| (format!("s{k}"), "SocketFloat", json!(k)))
        .collect();
    let ins: Vec<(&str, &str, Value)> = ins
        .iter()
        .map(|(a, b, c)| (a.as_str(), *b, c.clone()))
        .collect();
    t.node("geom_custom", &ins, &[]);
    let al: Aliases = serde_json::from_value(
        json!({"geom_custom": {"type": "value_float", "inputs": {"s10": "value"}}}),
    )
    .unwrap();
    let g = import(&t.json(), &al, &builtin_registry()).unwrap();
    let n = g.nodes.values().next().unwrap();
    assert_eq!(n.params["value"], json!(10.0));
    let _ = Path::new(".");
}

/// Read USD -> Apply Transform -> Mass Spring with the given switch values.
fn switches_tree(integrator: i64, liu13: i64) -> Value {
    let mut t = Tree::new();
    let geo = "SocketGeometry";
    let (_, read) = t.node(
        "geom_read_usd",
        &[
            ("File Name", "SocketString", json!("grid10x10.usda")),
            ("Prim Path", "SocketString", json!("/Grid/Grid")),
        ],
        &[("Geometry", geo)],
    );
    let (xin, xout) = t.node(
        "geom_apply_transform_geom",
        &[
            ("Geometry", geo, Value::Null),
            ("Translate Y", "SocketFloat", json!(2.0)),
            ("Rotate Z", "SocketFloat", json!(90.0)),
            ("Scale X", "SocketFloat", json!(3.0)),
        ],
        &[("Geometry", geo)],
    );
    t.link(read[0], xin[0]);
    let (min, _) = t.node(
        "geom_mass_spring",
        &[
            ("Mesh", geo, Value::Null),
            ("time integrator type", "SocketInt", json!(integrator)),
            ("enable damping", "SocketInt", json!(1)),
            ("enable debug output", "SocketInt", json!(1)),
            ("enable Liu13", "SocketInt", json!(liu13)),
        ],
        &[("Output Mesh", geo)],
    );
    t.link(xout[0], min[0]);
    t.json()
}

#[test]
fn switches_and_vector_components_translate() {
    let r = builtin_registry();
    let node = |g: &cgnodes::graph::GraphFile, ty: &str| {
        g.nodes
            .values()
            .find(|n| n.node_type == ty)
            .unwrap()
            .params
            .clone()
    };
    for (ti, liu, want) in [
        (0, 0, "implicit"),
        (1, 0, "semi_implicit"),
        (0, 1, "projective"),
        (1, 1, "projective"),
    ] {
        let g = import(&switches_tree(ti, liu), &Aliases::default(), &r).unwrap();
        let p = node(&g, "mass_spring");
        assert_eq!(p["integrator"], json!(want), "type {ti}, Liu13 {liu}");
        assert_eq!(p["damped"], json!(true));
        assert_eq!(p["debug"], json!(true));
        let x = node(&g, "mesh_transform");
        assert_eq!(x["translate"], json!([0.0, 2.0, 0.0]));
        assert_eq!(x["rotate"], json!([0.0, 0.0, 90.0]));
        assert_eq!(x["scale"], json!([3.0, 1.0, 1.0]));
    }
    let e = import(&switches_tree(5, 0), &Aliases::default(), &r)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("'time integrator type' = 5") && e.contains("known: 0, 1"),
        "{e}"
    );
}
