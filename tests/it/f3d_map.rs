//! Framework3D's node types: every built-in map names real cgnodes sockets, each mapped type
//! imports, the docs' table is the generated one, unsupported nodes are warnings, and the
//! new geometry nodes run behind their Framework3D names.

use cgnodes::exec::{Executor, RunOptions};
use cgnodes::f3d::{import, node_maps, table::map_table, warnings, Aliases};
use cgnodes::node::FileEnv;
use cgnodes::nodes::builtin_registry;
use serde_json::{json, Value};

use crate::common::root;

fn read(rel: &str) -> Value {
    serde_json::from_str(&std::fs::read_to_string(root().join(rel)).unwrap()).unwrap()
}

#[test]
fn docs_table_is_the_generated_one() {
    let maps = node_maps(&Aliases::default()).unwrap();
    let want = map_table(&maps, true);
    let doc = std::fs::read_to_string(root().join("docs/framework3d.md")).unwrap();
    let (begin, end) = ("<!-- f3d-map:begin -->\n", "<!-- f3d-map:end -->");
    let a = doc.find(begin).expect("begin marker") + begin.len();
    let b = doc.find(end).expect("end marker");
    assert_eq!(
        &doc[a..b],
        want,
        "regenerate with: cgnodes import-f3d --list-map --markdown"
    );
}

/// The socket a target names (`socket`, `socket[k]`, `socket<h.in:out`, `socket>h.in:out`).
fn base(t: &str) -> &str {
    let t = t.split(['<', '>']).next().unwrap();
    t.split('[').next().unwrap()
}

#[test]
fn every_map_names_real_sockets_and_imports() {
    let reg = builtin_registry();
    let maps = node_maps(&Aliases::default()).unwrap();
    let mut mapped = 0;
    for (id, m) in &maps {
        if m.unsupported.is_some() {
            assert!(m.node_type.is_none(), "{id}: unsupported maps have no type");
            continue;
        }
        let Some(ty) = &m.node_type else { continue };
        let d = reg
            .get(ty)
            .unwrap_or_else(|| panic!("{id}: no node '{ty}'"));
        for t in m.inputs.values().flatten() {
            assert!(
                d.input(base(t)).is_some(),
                "{id}: '{ty}' has no input '{t}'"
            );
        }
        for t in m.outputs.values().flatten() {
            assert!(
                d.output(base(t)).is_some(),
                "{id}: '{ty}' has no output '{t}'"
            );
        }
        for t in m.inputs.values().chain(m.outputs.values()).flatten() {
            if let Some((_, h)) = t.split_once(['<', '>']) {
                let (ht, rest) = h.split_once('.').unwrap();
                let (hi, ho) = rest.split_once(':').unwrap();
                let hd = reg
                    .get(ht)
                    .unwrap_or_else(|| panic!("{id}: no helper '{ht}'"));
                assert!(
                    hd.input(hi).is_some() && hd.output(ho).is_some(),
                    "{id}: {t}"
                );
            }
        }
        // A one-node tree of this type with every mapped socket imports onto `ty`.
        let mut sockets = serde_json::Map::new();
        let (mut ins, mut outs) = (serde_json::Map::new(), serde_json::Map::new());
        let mut next = 2;
        for (k, name) in m.inputs.keys().enumerate() {
            sockets.insert(
                next.to_string(),
                json!({"ID": next, "identifier": name, "in_out": 1}),
            );
            ins.insert(k.to_string(), json!(next));
            next += 1;
        }
        for (k, name) in m.outputs.keys().enumerate() {
            sockets.insert(
                next.to_string(),
                json!({"ID": next, "identifier": name, "in_out": 0}),
            );
            outs.insert(k.to_string(), json!(next));
            next += 1;
        }
        let tree = json!({"links_info": {}, "sockets_info": sockets,
            "nodes_info": {"1": {"ID": 1, "id_name": id, "inputs": ins, "outputs": outs}}});
        let g = import(&tree, &Aliases::default(), &reg).unwrap_or_else(|e| panic!("{id}: {e}"));
        let n = g
            .nodes
            .values()
            .find(|n| {
                n.meta
                    .as_ref()
                    .is_some_and(|m| m["f3d_id_name"] == json!(id))
            })
            .unwrap_or_else(|| panic!("{id}: no imported node"));
        assert_eq!(&n.node_type, ty);
        mapped += 1;
    }
    assert!(mapped >= 35, "{mapped} mapped types");
}

#[test]
fn geometry_family_runs_and_warns_for_the_debug_view() {
    let reg = builtin_registry();
    let tree = read("tests/data/f3d/geometry_family.json");
    let g = import(&tree, &Aliases::default(), &reg).unwrap();
    // Widget values carried over.
    assert_eq!(g.nodes["create_grid_1"].params["resolution"], json!(3));
    assert_eq!(g.nodes["create_grid_1"].params["size"], json!(2.0));
    assert_eq!(g.nodes["random_uv_points_70"].params["count"], json!(7));
    assert_eq!(g.nodes["random_uv_points_70"].params["seed"], json!(5));
    assert_eq!(g.nodes["random_uv_points_70"].params["width"], json!(0.25));
    assert_eq!(g.nodes["Triangulate_50"].node_type, "mesh_triangulate");
    assert_eq!(g.nodes["print_debug_info_60"].node_type, "mesh_info");
    assert!(!g.nodes.contains_key("visualize_neighbor_search_80"));
    let w = warnings(&g);
    assert!(
        w.iter()
            .any(|w| w.starts_with("geom_visualize_neighbor_search (node 80) is not run")),
        "{w:?}"
    );
    // Runs end to end: the flat grid's curvature is 0 in the interior, so the written colours
    // are the colour map of the curvature computed directly.
    let dir = tempfile::tempdir().unwrap();
    let gfile = cgnodes::graph::Graph {
        file: dir.path().join("g.json"),
        dir: dir.path().to_path_buf(),
        spec: g,
        hash: String::new(),
    };
    let valid = cgnodes::validate::validate(&gfile, &reg).unwrap_or_else(|e| panic!("{e:?}"));
    let out = dir.path().join("out");
    let opts = RunOptions {
        files: FileEnv {
            graph_dir: dir.path().to_path_buf(),
            out_dir: out.clone(),
            ..Default::default()
        },
        ..Default::default()
    };
    let r = Executor::new(Some(1), None).unwrap().run(&valid, &opts, 0);
    assert!(r.ok(), "{:?}", r.errors());
    let m = cgnodes::nodes::mesh::mesh_load::load_mesh(
        &out.join("grid.usda"),
        &cgnodes::nodes::mesh::mesh_load::LoadOptions {
            prim: "/grid".into(),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(m.num_vertices(), 16);
    let grid = std::sync::Arc::new(cgnodes::nodes::mesh::create_grid::create_grid(3, 2.0).unwrap());
    let k = cgnodes::nodes::mesh::gaussian_curvature::gaussian_curvature(&grid).unwrap();
    let want = cgnodes::nodes::mesh::signed_color_map::signed_color_map(&k);
    let got = &m.colors.as_ref().expect("colours written").values;
    for (g, w) in got.iter().zip(&want) {
        for c in 0..3 {
            assert!((g[c] - w[c]).abs() < 1e-5, "{g:?} against {w:?}");
        }
    }
    for (p, q) in m.positions.iter().zip(&grid.positions) {
        assert!((0..3).all(|c| (p[c] - q[c]).abs() < 1e-6));
    }
}

#[test]
fn composition_family_maps_lights_and_warns() {
    let reg = builtin_registry();
    let g = import(
        &read("tests/data/f3d/composition_family.json"),
        &Aliases::default(),
        &reg,
    )
    .unwrap();
    let l = &g.nodes["comp_add_point_light_20"];
    assert_eq!(l.node_type, "stage_light");
    assert_eq!(l.params["kind"], json!("point"));
    assert_eq!(l.params["position"], json!([1.5, -2.0, 3.0]));
    assert_eq!(l.params["color"], json!([0.5, 0.25, 1.0]));
    assert_eq!(l.params["radius"], json!(0.1));
    assert_eq!(l.params["path"], json!("Light"));
    let r = &g.nodes["comp_read_usd_1"];
    assert_eq!(r.node_type, "stage_read");
    assert_eq!(r.params["path"], json!("sphere.usda"));
    let m = &g.nodes["comp_merge_to_global_10"];
    assert_eq!(m.node_type, "stage_merge");
    assert_eq!(m.params["path"], json!("Scene"));
    assert_eq!(
        m.inputs["layer"],
        cgnodes::graph::format::LinkSpec::One("comp_read_usd_1.layer".into())
    );
    let d = &g.nodes["comp_add_dome_light_30"];
    assert_eq!(
        (&d.params["kind"], &d.params["file"]),
        (&json!("dome"), &json!("garden.exr"))
    );
    assert!(warnings(&g).is_empty(), "{:?}", warnings(&g));
}

#[test]
fn hw9_render_and_composition_graphs_import_with_warnings() {
    let reg = builtin_registry();
    // Every node of the render graph is mapped: the stage readers, the rasterizer, the two
    // shading passes (transparent refraction into the environment pass) and present.
    let g = import(
        &read("assets/course/hw9/RenderGraph.json"),
        &Aliases::default(),
        &reg,
    )
    .unwrap();
    let not_run = warnings(&g)
        .iter()
        .filter(|w| w.contains(") is not run:"))
        .count();
    assert_eq!(not_run, 0, "{:?}", warnings(&g));
    let mut types: Vec<&str> = g.nodes.values().map(|n| n.node_type.as_str()).collect();
    types.sort();
    types.dedup();
    assert_eq!(
        types,
        [
            "environment_pass",
            "image_save",
            "render_raster",
            "stage_load",
            "transparent_refraction"
        ]
    );
    for id in [
        "render_scene_camera_13",
        "render_scene_meshes_19",
        "render_scene_lights_36",
    ] {
        assert_eq!(g.nodes[id].node_type, "stage_load", "{id}");
    }
    let r = &g.nodes["render_rasterize_impl_1"];
    assert_eq!(r.node_type, "render_raster");
    assert_eq!(
        r.inputs["camera"],
        cgnodes::graph::format::LinkSpec::One("render_scene_camera_13.camera".into())
    );
    assert_eq!(g.nodes["render_present_50"].node_type, "image_save");
    let g = import(
        &read("assets/course/hw9/CompositionGraph.json"),
        &Aliases::default(),
        &reg,
    )
    .unwrap();
    assert!(warnings(&g).is_empty(), "{:?}", warnings(&g));
    let d = &g.nodes["comp_add_dome_light_1"];
    assert_eq!(d.params["color"], json!([1.0, 1.0, 2.013000011444092]));
    assert_eq!(d.params["file"], json!("garden.exr"));
    assert_eq!(d.params["path"], json!("DomeLight"));
    // Framework3D saves an untouched editor with null parts: imported, reported empty.
    let t = json!({"links_info": null, "nodes_info": null, "sockets_info": null});
    let g = import(&t, &Aliases::default(), &reg).unwrap();
    assert_eq!(
        warnings(&g),
        vec!["the graph is empty (no nodes saved)".to_string()]
    );
}

/// The course's hw8 pattern: every widget of Mass Spring reaches the cgnodes node, compared
/// with the values in the file (switches as booleans, the integrator switch as its name);
/// `func_create_float3f` is one vec3 linked into `sphere_center`.
#[test]
fn hw8_mass_spring_widgets_carry_over() {
    let reg = builtin_registry();
    let mut tree = read("tests/data/f3d/hw8_mass_spring.json");
    let widget = |tree: &Value, ident: &str| -> Value {
        tree["sockets_info"]
            .as_object()
            .unwrap()
            .values()
            .find(|s| s["identifier"] == json!(ident) && s.get("value").is_some())
            .map(|s| s["value"].clone())
            .unwrap()
    };
    let g = import(&tree, &Aliases::default(), &reg).unwrap();
    let p = &g.nodes["mass_spring_20"].params;
    for (f3d, ours) in [
        ("stiffness", "stiffness"),
        ("h", "h"),
        ("damping", "damping"),
        ("gravity", "gravity"),
        ("collision penalty_k", "penalty_k"),
        ("collision scale factor", "collision_scale"),
        ("sphere radius", "sphere_radius"),
    ] {
        assert_eq!(p[ours], widget(&tree, f3d), "{f3d}");
    }
    for (f3d, ours) in [
        ("enable time profiling", "profile"),
        ("enable damping", "damped"),
        ("enable debug output", "debug"),
        ("enable sphere collision", "sphere"),
    ] {
        assert_eq!(p[ours], json!(widget(&tree, f3d) != json!(0)), "{f3d}");
    }
    assert_eq!(p["integrator"], json!("semi_implicit"));
    // no widget fixes vertices: the pair Framework3D's MassSpring constructor fixes
    assert_eq!(p["fixed"], json!("first_row_ends"));
    assert_eq!(
        g.nodes["mass_spring_20"].inputs["sphere_center"].links()[0].to_string(),
        "create_float3f_10.value"
    );
    assert_eq!(
        g.nodes["create_float3f_10"].params["value"],
        json!([0.0, 0.25, -1.5])
    );
    assert_eq!(g.nodes["create_float3f_10"].node_type, "value_vec3");
    // Liu13 switched on selects the projective integrator.
    for s in tree["sockets_info"].as_object_mut().unwrap().values_mut() {
        if s["identifier"] == json!("enable Liu13") {
            s["value"] = json!(1);
        }
    }
    let g = import(&tree, &Aliases::default(), &reg).unwrap();
    assert_eq!(
        g.nodes["mass_spring_20"].params["integrator"],
        json!("projective")
    );
}

/// Create Buffer3f and Create Buffer1i (Framework3D's `func_create_buffer*`): the widget
/// values become the repeat nodes' parameters, and `repeat` gives `Size` copies.
#[test]
fn create_buffer_widgets_become_repeat_nodes() {
    let reg = builtin_registry();
    let sock = |id: i64, ident: &str, inout: i64, v: Value| {
        let mut s = json!({"ID": id, "identifier": ident, "in_out": inout});
        if !v.is_null() {
            s["value"] = v;
        }
        (id.to_string(), s)
    };
    let sockets: serde_json::Map<String, Value> = [
        sock(2, "X", 1, json!(1.5)),
        sock(3, "Y", 1, json!(-2.0)),
        sock(4, "Z", 1, json!(3.25)),
        sock(5, "Size", 1, json!(4)),
        sock(6, "Buffer", 0, Value::Null),
        sock(12, "X", 1, json!(7)),
        sock(13, "Size", 1, json!(3)),
        sock(14, "Buffer", 0, Value::Null),
    ]
    .into_iter()
    .collect();
    let tree = json!({"links_info": {}, "sockets_info": sockets, "nodes_info": {
        "1": {"ID": 1, "id_name": "func_create_buffer3f", "inputs": {"0": 2, "1": 3, "2": 4, "3": 5}, "outputs": {"0": 6}},
        "11": {"ID": 11, "id_name": "func_create_buffer1i", "inputs": {"0": 12, "1": 13}, "outputs": {"0": 14}}}});
    let g = import(&tree, &Aliases::default(), &reg).unwrap();
    let b3 = &g.nodes["create_buffer3f_1"];
    assert_eq!(b3.node_type, "buffer_repeat3");
    assert_eq!(
        [
            &b3.params["x"],
            &b3.params["y"],
            &b3.params["z"],
            &b3.params["size"]
        ],
        [&json!(1.5), &json!(-2.0), &json!(3.25), &json!(4)]
    );
    let b1 = &g.nodes["create_buffer1i_11"];
    assert_eq!(b1.node_type, "buffer_repeat_int");
    assert_eq!(
        (&b1.params["x"], &b1.params["size"]),
        (&json!(7), &json!(3))
    );
    // The repeat function itself: Size copies of the value.
    assert_eq!(
        cgnodes::nodes::mesh::buffer::repeat([1.5, -2.0, 3.25], 4),
        vec![[1.5, -2.0, 3.25]; 4]
    );
}
