//! The golden image, pass selection (only the asked passes are produced, colour unchanged)
//! and the `render_raster` node's cache when other passes are wanted later.

use cgnodes::exec::{Executor, NodeStatus, RunOptions, RunReport};
use cgnodes::nodes::builtin_registry;
use cgnodes::nodes::image::image_load::{decode_image, ColorSpace};
use cgnodes::nodes::image::image_save::{encode_image, ImageFileFormat};
use cgnodes::nodes::mesh::mesh_plane::plane_mesh;
use cgnodes::nodes::render::raster::{render, Passes, RasterOptions};
use cgnodes::types::*;
use cgnodes::validate::validate;
use std::path::Path;
use std::sync::Arc;

/// The golden scene: a checkered ground, a sphere-like closed mesh (bunny), a point and
/// a directional light with shadows, 4x MSAA.
fn golden_scene() -> (Scene, Camera) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let tex_bytes = std::fs::read(root.join("assets/course/green_checkerboard.png")).unwrap();
    let tex = decode_image(&tex_bytes, ColorSpace::Srgb).unwrap();
    let bunny = cgnodes::nodes::mesh::mesh_load::load_mesh(
        &root.join("assets/meshes/bunny_closed.obj"),
        &Default::default(),
    )
    .unwrap();
    // Scale the bunny (about 0.15 tall) up 10x and stand it on y = 0.
    let (lo, _) = bunny.bounds();
    let mut b = bunny.clone();
    for p in &mut b.positions {
        *p = [10.0 * p[0], 10.0 * (p[1] - lo[1]), 10.0 * p[2]];
    }
    let scene = Scene {
        objects: vec![
            SceneObject {
                mesh: Arc::new(plane_mesh(6.0, [0.0; 3], 1, 3.0)),
                material: Some(Arc::new(Material {
                    base_color: [1.0; 3],
                    base_color_texture: Some(Arc::new(tex)),
                    ..Default::default()
                })),
            },
            SceneObject {
                mesh: Arc::new(b),
                material: Some(Arc::new(Material {
                    base_color: [0.8, 0.35, 0.2],
                    metallic: 0.4,
                    roughness: 0.35,
                    ..Default::default()
                })),
            },
        ],
        lights: vec![
            Light::Directional {
                direction: [-1.0, -2.0, -0.7],
                color: [1.0, 0.95, 0.9],
                intensity: 0.8,
            },
            Light::Point {
                position: [1.5, 2.5, 2.0],
                color: [0.9, 0.95, 1.0],
                intensity: 6.0,
            },
        ],
        camera: None,
    };
    let cam = Camera {
        eye: [0.5, 2.2, 4.0],
        target: [0.0, 0.6, 0.0],
        width: 128,
        height: 96,
        ..Default::default()
    };
    (scene, cam)
}

#[test]
fn golden_image_matches_within_tolerance() {
    let (scene, cam) = golden_scene();
    let opts = RasterOptions {
        shadow_resolution: 1024,
        ..Default::default()
    };
    let out = render(&scene, &cam, &opts).unwrap();
    let png = encode_image(&out.color, ImageFileFormat::Png, 0.0, 0.0).unwrap();
    let got = decode_image(&png, ColorSpace::Raw).unwrap();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/render/golden_raster.png");
    // Blessing writes the golden and fails: a run that rewrote the golden compared nothing.
    if std::env::var_os("CGNODES_BLESS").is_some() {
        std::fs::write(&path, &png).unwrap();
        panic!(
            "CGNODES_BLESS: wrote {}; check it by eye, then run this test again without \
             CGNODES_BLESS to compare",
            path.display()
        );
    }
    let want = decode_image(&std::fs::read(&path).unwrap(), ColorSpace::Raw).unwrap();
    assert_eq!((got.width, got.height), (want.width, want.height));
    let mut sum = 0.0;
    let mut bad = 0;
    for (a, b) in got.pixels.iter().zip(&want.pixels) {
        for k in 0..3 {
            let d = (a[k] - b[k]).abs() as f64;
            sum += d;
            if d > 8.0 / 255.0 {
                bad += 1;
            }
        }
    }
    let mean = sum / (3.0 * got.pixels.len() as f64);
    // Floating-point differences across platforms move a few edge pixels by a step or two.
    assert!(
        mean < 1.0 / 255.0 && bad < 30,
        "mean {mean}, {bad} channels off by > 8/255"
    );
}

#[test]
fn only_the_asked_passes_are_produced_and_colour_does_not_change() {
    let (scene, cam) = golden_scene();
    let all = render(&scene, &cam, &RasterOptions::default()).unwrap();
    let colour = RasterOptions {
        passes: Passes::COLOR,
        ..Default::default()
    };
    let only = render(&scene, &cam, &colour).unwrap();
    assert_eq!(only.color.pixels, all.color.pixels);
    assert_eq!(only.shaded, all.shaded);
    for pass in [
        &only.depth,
        &only.normal,
        &only.position,
        &only.uv,
        &only.base_color,
    ] {
        assert_eq!((pass.width, pass.height, pass.pixels.len()), (0, 0, 0));
    }
    // Depth alone: no shading, and the same depth as with every pass.
    let depth = RasterOptions {
        passes: Passes {
            depth: true,
            ..Passes::NONE
        },
        ..Default::default()
    };
    let d = render(&scene, &cam, &depth).unwrap();
    assert_eq!(d.depth.pixels, all.depth.pixels);
    assert!(d.color.pixels.is_empty());
    assert_eq!(d.shaded, 0);
}

/// A ground plane facing +Z seen straight on from z = 3: depth 3 wherever it is hit.
const PLANE_GRAPH: &str = r#"{
  "format": "cgnodes-graph",
  "version": 1,
  "nodes": {
    "ground": {"type": "mesh_plane", "params": {"size": 20.0, "up": "z"}},
    "sun": {"type": "light_directional", "params": {"direction": [0.0, 0.0, -1.0]}},
    "cam": {"type": "camera", "params": {"eye": [0.0, 0.0, 3.0], "target": [0.0, 0.0, 0.0], "fov": 40.0, "width": 32, "height": 24}},
    "scene": {"type": "scene", "inputs": {"meshes": ["ground.mesh"], "lights": ["sun.light"], "camera": "cam.camera"}},
    "render": {"type": "render_raster", "params": {"shadow_resolution": 256}, "inputs": {"scene": "scene.scene"}}
  }
}"#;

fn image_of(r: &RunReport, socket: &str) -> Option<Arc<Image>> {
    match r.output("render", socket) {
        Some(Value::Image(i)) => Some(i.clone()),
        _ => None,
    }
}

#[test]
fn render_node_skips_unwanted_passes_and_the_cache_reruns_for_them() {
    let g = cgnodes::graph::parse(PLANE_GRAPH, Path::new("inline.json"), Path::new("."))
        .expect("parses");
    let valid = validate(&g, &builtin_registry()).expect("validates");
    let exec = Executor::new(None, None).unwrap();
    let reading = |socket: &str| RunOptions {
        targets: Some(Vec::new()),
        read_outputs: vec![format!("render.{socket}")],
        ..Default::default()
    };
    let status = |r: &RunReport| r.node("render").map(|n| n.status.clone());
    // 1: only the colour is wanted, so no other pass is produced.
    let r1 = exec.run(&valid, &reading("color"), 0);
    assert!(r1.ok(), "{:?}", r1.errors());
    assert!(matches!(status(&r1), Some(NodeStatus::Ran)));
    let color = image_of(&r1, "color").expect("colour produced");
    assert_eq!((color.width, color.height), (32, 24));
    for socket in ["depth", "normal", "position", "uv", "base_color"] {
        assert!(image_of(&r1, socket).is_none(), "{socket} was computed");
    }
    // 2: the same inputs, now wanting depth: the cached entry lacks it, so the node reruns.
    let r2 = exec.run(&valid, &reading("depth"), 0);
    assert!(r2.ok(), "{:?}", r2.errors());
    assert!(matches!(status(&r2), Some(NodeStatus::Ran)));
    let depth = image_of(&r2, "depth").expect("depth produced");
    assert_eq!((depth.width, depth.height), (32, 24));
    for p in &depth.pixels {
        assert!((p[0] - 3.0).abs() < 1e-5 && p[3] == 1.0, "{p:?}");
    }
    // 3 and 4: the entry now holds colour and depth; both are served from the cache.
    let r3 = exec.run(&valid, &reading("color"), 0);
    assert!(matches!(status(&r3), Some(NodeStatus::Cached)));
    assert_eq!(image_of(&r3, "color").unwrap().pixels, color.pixels);
    let r4 = exec.run(&valid, &reading("depth"), 0);
    assert!(matches!(status(&r4), Some(NodeStatus::Cached)));
    assert_eq!(image_of(&r4, "depth").unwrap().pixels, depth.pixels);
    // A node read whole (`render`) computes every pass, and reruns for the missing ones.
    let whole = RunOptions {
        targets: Some(Vec::new()),
        read_outputs: vec!["render".into()],
        ..Default::default()
    };
    let r5 = exec.run(&valid, &whole, 0);
    assert!(matches!(status(&r5), Some(NodeStatus::Ran)));
    assert!(image_of(&r5, "normal").is_some() && image_of(&r5, "uv").is_some());
}
