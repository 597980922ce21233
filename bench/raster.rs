//! Rasterizer benchmark: `igea_front` (154k triangles) on a ground plane at 1920x1080
//! with 4x anti-aliasing and two 2048^2 directional shadow maps.
//!
//! Run: `cargo bench --bench raster` (reads assets/meshes/igea_front.obj, or
//! the path in CGNODES_IGEA). Prints the minimum and median milliseconds of five renders,
//! triangles per second and shaded pixels per second, with the same scene under 1x
//! sampling without shadows as the baseline measured in the same run, the target line
//! with only the colour and with all six passes (what a graph linking only `color`, or
//! every output, computes), and 4x supersampling for comparison. `CGNODES_BENCH_PHASES=1`
//! prints the profile by stages instead (flattening, the shadow maps, and the render with
//! only the depth pass, colour without shadows and colour with them; wall and CPU ms).

use cgnodes::nodes::mesh::mesh_load::{load_mesh, LoadOptions};
use cgnodes::nodes::mesh::mesh_plane::plane_mesh;
use cgnodes::nodes::render::raster::geometry::scene_geometry;
use cgnodes::nodes::render::raster::shadow::directional_shadow_map;
use cgnodes::nodes::render::raster::{render, AntiAliasing, Passes, RasterOptions};
use cgnodes::types::*;
use std::sync::Arc;
use std::time::Instant;

/// This process's CPU time (user + system) in seconds, from /proc/self/stat (Linux; 0
/// elsewhere). On a loaded machine wall time overstates the cost; CPU time / threads
/// estimates the wall time on idle cores.
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    let Some(rest) = stat.rsplit(')').next() else {
        return 0.0;
    };
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    // Fields 14 and 15 (utime, stime) are at 11 and 12 after the command name.
    (ticks(11) + ticks(12)) / 100.0
}

fn main() {
    let path =
        std::env::var("CGNODES_IGEA").unwrap_or_else(|_| "assets/meshes/igea_front.obj".into());
    let mesh = match load_mesh(std::path::Path::new(&path), &LoadOptions::default()) {
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
        passes: Passes::COLOR,
        ..Default::default()
    };
    let all = RasterOptions {
        passes: Passes::ALL,
        ..full.clone()
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
    const RUNS: usize = 5;
    if std::env::var("CGNODES_BENCH_PHASES").is_ok() {
        phases(&scene, &cam, &full, RUNS);
        return;
    }
    let mut base_ms = 0.0;
    // CGNODES_BENCH_ONLY=TEXT runs only the lines whose name contains TEXT (for profiling).
    let only = std::env::var("CGNODES_BENCH_ONLY").unwrap_or_default();
    for (name, o) in [
        ("1x, no shadows (baseline), colour", &base),
        ("4x MSAA, two 2048^2 shadows, colour", &full),
        ("4x MSAA, two 2048^2 shadows, 6 passes", &all),
        ("4x SSAA, two 2048^2 shadows, colour", &ssaa),
    ] {
        if !only.is_empty() && !name.contains(only.as_str()) {
            continue;
        }
        let _ = render(&scene, &cam, o).expect("render"); // warm-up
        let mut times = Vec::new();
        let mut shaded = 0;
        let cpu0 = cpu_seconds();
        for _ in 0..RUNS {
            let t = Instant::now();
            let out = render(&scene, &cam, o).expect("render");
            times.push(t.elapsed().as_secs_f64());
            shaded = out.shaded;
        }
        let cpu_ms = (cpu_seconds() - cpu0) / RUNS as f64 * 1e3;
        times.sort_by(|a, b| a.total_cmp(b));
        let t = times[RUNS / 2];
        if base_ms == 0.0 {
            base_ms = t * 1e3;
        }
        println!(
            "{name:38} {:7.1} ms min {:7.1} ms median of {RUNS}, {:7.1} ms CPU  {:5.2} Mtri/s  {:5.2} M shaded px/s  {:5.2}x baseline",
            times[0] * 1e3,
            t * 1e3,
            cpu_ms,
            ntris as f64 / t / 1e6,
            shaded as f64 / t / 1e6,
            t * 1e3 / base_ms
        );
    }
}

/// Median wall milliseconds of `runs` calls of `f` after a warm-up, and the mean CPU
/// milliseconds per call.
fn median_ms<T>(runs: usize, mut f: impl FnMut() -> T) -> (f64, f64) {
    let _ = f();
    let cpu0 = cpu_seconds();
    let mut t: Vec<f64> = (0..runs)
        .map(|_| {
            let t0 = Instant::now();
            let _ = std::hint::black_box(f());
            t0.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    let cpu = (cpu_seconds() - cpu0) / runs as f64 * 1e3;
    t.sort_by(|a, b| a.total_cmp(b));
    (t[runs / 2], cpu)
}

/// The profile by phases (`CGNODES_BENCH_PHASES=1`): each stage of the target line timed on
/// its own through the public API (median of `runs`), and the whole render with and without
/// shadows; shading with shadow lookups is what the last two differ by beyond the maps.
fn phases(scene: &Scene, cam: &Camera, full: &RasterOptions, runs: usize) {
    let g = scene_geometry(scene).expect("geometry");
    let geo = median_ms(runs, || scene_geometry(scene).expect("geometry"));
    let dirs: Vec<[f64; 3]> = scene
        .lights
        .iter()
        .filter_map(|l| match l {
            Light::Directional { direction, .. } => Some(*direction),
            _ => None,
        })
        .collect();
    let maps = median_ms(runs, || {
        dirs.iter()
            .map(|&d| directional_shadow_map(&g.pos, d, g.bounds, full.shadow_resolution))
            .collect::<Vec<_>>()
    });
    let noshadow = RasterOptions {
        shadows: false,
        ..full.clone()
    };
    let unlit = RasterOptions {
        passes: Passes {
            depth: true,
            ..Passes::NONE
        },
        ..full.clone()
    };
    let r_unlit = median_ms(runs, || render(scene, cam, &unlit).expect("render"));
    let r_nosh = median_ms(runs, || render(scene, cam, &noshadow).expect("render"));
    let r_full = median_ms(runs, || render(scene, cam, full).expect("render"));
    println!("phases of the target line (wall ms median of {runs} on the pool, CPU ms mean):");
    for (name, (wall, cpu)) in [
        ("flatten geometry (scene_geometry)", geo),
        ("two 2048^2 shadow maps, one after the other", maps),
        ("render, depth pass only (no lighting, no maps)", r_unlit),
        ("render, colour without shadows", r_nosh),
        ("render, colour with shadows (target line)", r_full),
    ] {
        println!("  {name:48} {wall:7.1} wall {cpu:7.1} CPU");
    }
}
