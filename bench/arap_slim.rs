//! Fold-free ARAP beside libigl's SLIM (symmetric Dirichlet), both from the same Tutte map.
//!
//! `cargo bench --bench arap_slim [-- ITERATIONS [MESH.obj ...]]` (default 20 SLIM iterations;
//! meshes: bunny_base (one loop, deep concavities), bunny_open (three loops), beetle_11holes
//! (eleven loops) and camelhead (deep concavities) from `assets/meshes/`; others, such as
//! `nefertiti_open4` from `bench/peers/arap_meshes.py`, one argument away). For each mesh: the `arap` node's start (Tutte, mean-value
//! weights, circle, holes filled), then ours fold-free with tolerance 0 stopped after 1, 2, 5,
//! 10, 20, 50 and 100 iterations (one run per length, its time from the start of
//! `arap_parameterize`: frames, factorization and iterations), and `igl.slim_solve` one
//! iteration at a time from the same map (`bench/peers/arap_slim.py`, its time from
//! `slim_precompute`). The same numpy code measures both: ARAP energy (as minimized, UVs
//! unscaled), worst triangle (largest singular-value ratio), flips. Writes
//! `target/bench/arap_slim/*.slim.csv` and the charts `docs/charts/arap_slim_energy.svg` and
//! `docs/charts/arap_slim_worst.svg` (time on a log axis).

use cgnodes::chart::{draw, Chart, Series};
use cgnodes::nodes::mesh::obj::load_obj;
use cgnodes::nodes::param::arap::{arap_parameterize, ArapOptions};
use cgnodes::nodes::param::tutte::{tutte_parameterize, BoundaryShape, TutteWeights};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

const CHECKPOINTS: [usize; 7] = [1, 2, 5, 10, 20, 50, 100];

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let iterations: usize = args.first().and_then(|a| a.parse().ok()).unwrap_or(20);
    let out = root.join("target/bench/arap_slim");
    std::fs::create_dir_all(&out).expect("create target/bench/arap_slim");
    let mut meshes: Vec<PathBuf> = args.iter().skip(1).map(PathBuf::from).collect();
    if meshes.is_empty() {
        for m in ["bunny_base", "bunny_open", "beetle_11holes", "camelhead"] {
            meshes.push(root.join(format!("assets/meshes/{m}.obj")));
        }
    }
    let mut energy = Chart {
        title:
            "ARAP energy against time, fold-free ARAP (ours) and SLIM (libigl), same Tutte start"
                .into(),
        x_label: "ms".into(),
        y_label: "ARAP energy (as minimized)".into(),
        log_x: true,
        log_y: true,
        ..Default::default()
    };
    let mut worst = Chart {
        title: "worst triangle (largest singular-value ratio) against time".into(),
        x_label: "ms".into(),
        y_label: "max sigma1 / sigma2".into(),
        log_x: true,
        log_y: true,
        ..Default::default()
    };
    for path in meshes {
        let Some(name) = path.file_stem().map(|s| s.to_string_lossy().to_string()) else {
            continue;
        };
        if !path.exists() {
            eprintln!("{}: missing", path.display());
            continue;
        }
        let mesh = Arc::new(load_obj(&path, "").expect("load mesh")).triangulated();
        let tris = mesh.triangles().expect("triangles");
        let init = tutte_parameterize(&mesh, TutteWeights::MeanValue, BoundaryShape::Circle, true)
            .expect("tutte");
        let prefix = out.join(&name);
        let write_f64 = |ext: &str, xs: &mut dyn Iterator<Item = f64>| {
            let bytes: Vec<u8> = xs.flat_map(f64::to_le_bytes).collect();
            std::fs::write(prefix.with_extension(ext), bytes).expect("write");
        };
        write_f64("v", &mut mesh.positions.iter().flatten().copied());
        write_f64("init", &mut init.iter().flatten().copied());
        let f: Vec<u8> = tris
            .iter()
            .flatten()
            .flat_map(|&i| (i as i32).to_le_bytes())
            .collect();
        std::fs::write(prefix.with_extension("f"), f).expect("write");
        let mut checkpoints = Vec::new();
        for k in CHECKPOINTS {
            let opts = ArapOptions {
                iterations: k,
                tolerance: 0.0,
                ..Default::default()
            };
            let r = arap_parameterize(&mesh.positions, &tris, &init, &opts).expect("arap");
            let ms = r.log.last().map_or(0.0, |x| x.elapsed_ms);
            write_f64(&format!("ours.{k}"), &mut r.uv.iter().flatten().copied());
            checkpoints.push(format!("[{k}, {ms:.3}]"));
            eprintln!(
                "{name} ({} faces): ours {k} iterations ({} done, stop {}) in {ms:.1} ms",
                tris.len(),
                r.log.len() - 1,
                r.stop_reason.as_str()
            );
        }
        std::fs::write(
            prefix.with_extension("ours.json"),
            format!("{{\"checkpoints\": [{}]}}", checkpoints.join(", ")),
        )
        .expect("write");
        let ok = Command::new("python3")
            .arg(root.join("bench/peers/arap_slim.py"))
            .arg(&prefix)
            .arg(iterations.to_string())
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            eprintln!("{name}: SLIM peer failed (pip install libigl)");
            continue;
        }
        let csv = std::fs::read_to_string(prefix.with_extension("slim.csv")).expect("csv");
        println!("{name} ({} faces)\n{csv}", tris.len());
        for line in csv.lines().skip(1) {
            let c: Vec<&str> = line.split(',').collect();
            let num = |i: usize| c.get(i).and_then(|x| x.parse::<f64>().ok());
            let (Some(ms), Some(e), Some(w)) = (num(2), num(3), num(4)) else {
                continue;
            };
            let label = format!("{name}: {}", c[0]);
            for (chart, y) in [(&mut energy, e), (&mut worst, w)] {
                if !(y.is_finite() && y > 0.0 && ms > 0.0) {
                    continue;
                }
                match chart.series.iter_mut().find(|s| s.label == label) {
                    Some(s) => s.points.push((ms, y)),
                    None => chart.series.push(Series {
                        label: label.clone(),
                        points: vec![(ms, y)],
                    }),
                }
            }
        }
    }
    let dir = root.join("docs/charts");
    let _ = std::fs::create_dir_all(&dir);
    for (chart, file) in [
        (&energy, "arap_slim_energy.svg"),
        (&worst, "arap_slim_worst.svg"),
    ] {
        match draw(chart, &dir.join(file)) {
            Ok(()) => eprintln!("chart: docs/charts/{file}"),
            Err(e) => eprintln!("chart {file}: {e}"),
        }
    }
}
