//! Rasterizer benchmark: `igea_front` (154k triangles) on a ground plane at 1920x1080
//! with 4x anti-aliasing and two 2048^2 directional shadow maps.
//!
//! Run: `cargo bench --bench raster` (reads /work/shared/assets/meshes/igea_front.obj, or
//! the path in CGNODES_IGEA). Prints milliseconds, triangles per second and shaded pixels
//! per second, with the same scene under 1x sampling without shadows as the baseline
//! measured in the same run, and 4x supersampling for comparison.

use cgnodes::nodes::mesh::load::load_obj;
use cgnodes::nodes::render::primitive::plane_mesh;
use cgnodes::nodes::render::raster::{render, AntiAliasing, RasterOptions};
use cgnodes::types::*;
use std::sync::Arc;
use std::time::Instant;

fn main() {
    let path = std::env::var("CGNODES_IGEA")
        .unwrap_or_else(|_| "/work/shared/assets/meshes/igea_front.obj".into());
    let mesh = match load_obj(std::path::Path::new(&path)) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("cannot load {path}: {e}");
            return;
        }
    };
    let (lo, hi) = mesh.bounds();
    let c: [f64; 3] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let size = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let mesh = Arc::new(mesh);
    let ntris = mesh.triangulated().num_faces();
    let scene = Scene {
        objects: vec![
            SceneObject {
                mesh: mesh.clone(),
                material: Some(Arc::new(Material {
                    base_color: [0.8, 0.7, 0.6],
                    metallic: 0.3,
                    roughness: 0.4,
                    ..Default::default()
                })),
            },
            SceneObject {
                mesh: Arc::new(plane_mesh(4.0 * size, [c[0], lo[1], c[2]], 1, 1.0)),
                material: None,
            },
        ],
        lights: vec![
            Light::Directional {
                direction: [-0.5, -1.0, -0.7],
                color: [1.0; 3],
                intensity: 0.8,
            },
            Light::Directional {
                direction: [0.8, -0.6, -0.4],
                color: [0.6, 0.7, 1.0],
                intensity: 0.5,
            },
        ],
        camera: None,
    };
    let cam = Camera {
        eye: [c[0] + 0.3 * size, c[1] + 0.2 * size, c[2] + 1.6 * size],
        target: c,
        width: 1920,
        height: 1080,
        fov_deg: 40.0,
        near: 1e-3 * size,
        far: 100.0 * size,
        ..Default::default()
    };
    let full = RasterOptions {
        samples_per_axis: 2,
        shadow_resolution: 2048,
        ..Default::default()
    };
    let ssaa = RasterOptions {
        aa: AntiAliasing::Supersampling,
        ..full.clone()
    };
    let base = RasterOptions {
        samples_per_axis: 1,
        shadows: false,
        ..full.clone()
    };
    println!(
        "raster bench: {ntris} triangles (+2 ground), 1920x1080, {} threads",
        rayon::current_num_threads()
    );
    let mut base_ms = 0.0;
    for (name, o) in [
        ("1x, no shadows (baseline)", &base),
        ("4x MSAA, two 2048^2 shadow maps", &full),
        ("4x SSAA, two 2048^2 shadow maps", &ssaa),
    ] {
        let _ = render(&scene, &cam, o).expect("render"); // warm-up
        let mut times = Vec::new();
        let mut shaded = 0;
        for _ in 0..3 {
            let t = Instant::now();
            let out = render(&scene, &cam, o).expect("render");
            times.push(t.elapsed().as_secs_f64());
            shaded = out.shaded;
        }
        times.sort_by(|a, b| a.total_cmp(b));
        let t = times[1];
        if base_ms == 0.0 {
            base_ms = t * 1e3;
        }
        println!(
            "{name:34} {:8.1} ms (median of 3)  {:6.2} Mtri/s  {:6.2} M shaded px/s  {:5.2}x baseline time",
            t * 1e3,
            ntris as f64 / t / 1e6,
            shaded as f64 / t / 1e6,
            t * 1e3 / base_ms
        );
    }
}
