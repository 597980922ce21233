//! Mass-spring speed beside NVIDIA Warp's CPU cloth benchmark, in the same run.
//! `cargo bench --bench cloth` (Warp is installed into target/peers-venv on first use; set
//! `CLOTH_SKIP_WARP=1` to skip it, `CLOTH_PYTHON` to choose the interpreter).
//!
//! Setup as `warp/examples/benchmarks/benchmark_cloth.py`: an n x n grid in the xz plane with
//! spacing 0.1, stretch, shear (both diagonals) and skip-one bending springs all k = 1000,
//! 0.1 kg per particle, the two corners of the first row fixed, gravity -9.81 along y,
//! 60 frames at 60 fps with 16 substeps. Differences: cgnodes runs in f64 (Warp in f32) and has
//! no per-spring dashpot (Warp's kd = 10); damping is off here. Reported: ms/frame for
//! `semi_implicit` (the same symplectic Euler as Warp's), and for `implicit` (one backward Euler
//! step per frame, h = 1/60) Newton steps per second and ms/frame; `projective` likewise.

use cgnodes::nodes::sim::mass_spring::grid::grid_mesh;
use cgnodes::nodes::sim::mass_spring::{
    springs_from_mesh, Method, Model, Simulator, SolverOptions, SpringKinds,
};
use std::time::Instant;

fn warp_model(n: usize) -> (Model, Vec<[f64; 3]>) {
    let s = 0.1 * (n - 1) as f64;
    let mesh = grid_mesh(n - 1, n - 1, [s, s], "xz", [s / 2.0, 0.0, s / 2.0], false).unwrap();
    let kinds = SpringKinds {
        shear: true,
        bending: true,
        bending_scale: 1.0,
    };
    let springs = springs_from_mesh(&mesh, 1000.0, kinds);
    let nv = mesh.num_vertices();
    let mut fixed = vec![false; nv];
    fixed[0] = true;
    fixed[n - 1] = true;
    let model = Model {
        springs,
        mass: vec![0.1; nv],
        fixed,
        gravity: [0.0, -9.81, 0.0],
        damping: 1.0,
    };
    (model, mesh.positions)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Runs `frames` frames of `substeps` steps, checking energy every step (as the node does,
/// for its log) or once per frame; returns per-frame ms and total iterations.
fn run(
    method: Method,
    n: usize,
    frames: usize,
    substeps: usize,
    per_step_energy: bool,
) -> (Vec<f64>, usize, usize) {
    let (model, x0) = warp_model(n);
    let springs = model.springs.len();
    let h = 1.0 / 60.0 / substeps as f64;
    let mut sim = Simulator::new(model, x0, None, method, h, SolverOptions::default()).unwrap();
    let mut ms = Vec::new();
    let mut iters = 0;
    for _ in 0..frames {
        let t = Instant::now();
        for _ in 0..substeps {
            iters += if per_step_energy {
                sim.step(None).expect("stable").iterations
            } else {
                sim.advance(None).expect("stable")
            };
        }
        if !per_step_energy {
            sim.check_energy(None).expect("stable");
        }
        ms.push(t.elapsed().as_secs_f64() * 1e3);
    }
    (ms, iters, springs)
}

fn warp() -> Option<serde_json::Value> {
    if std::env::var_os("CLOTH_SKIP_WARP").is_some() {
        return None;
    }
    let py = std::env::var("CLOTH_PYTHON").unwrap_or_else(|_| "python3".into());
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/bench/peers/cloth_warp.py");
    let out = std::process::Command::new(py).arg(script).output().ok()?;
    if !out.status.success() {
        eprintln!("warp benchmark failed: {}", String::from_utf8_lossy(&out.stderr));
        return None;
    }
    let text = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(text.lines().last()?).ok()
}

fn main() {
    let threads = rayon::current_num_threads();
    println!("cgnodes mass_spring, {threads} rayon threads; Warp CPU cloth benchmark settings");
    let w = warp();
    if let Some(w) = &w {
        println!("warp-lang {}", w["version"]);
    }
    println!(
        "| grid | springs | semi_implicit ms/frame, energy per frame (per step) | warp ms/frame (min / avg) | warp min / cgnodes |"
    );
    println!("|---|---|---|---|---|");
    for n in [32usize, 64, 128] {
        let (ms, _, springs) = run(Method::SemiImplicit, n, 60, 16, false);
        let ours = median(ms);
        let logged = median(run(Method::SemiImplicit, n, 60, 16, true).0);
        let (wmin, wavg) = w
            .as_ref()
            .map(|w| (w[n.to_string()]["min"].as_f64(), w[n.to_string()]["avg"].as_f64()))
            .unwrap_or((None, None));
        let f = |x: Option<f64>| x.map(|x| format!("{x:.2}")).unwrap_or("-".into());
        let ratio = wmin.map(|m| format!("{:.2}", m / ours)).unwrap_or("-".into());
        println!(
            "| {n}x{n} | {springs} | {ours:.2} ({logged:.2}) | {} / {} | {ratio} |",
            f(wmin),
            f(wavg)
        );
    }
    println!();
    println!("| grid | integrator | h | ms/frame (median) | iterations/step | Newton steps/s |");
    println!("|---|---|---|---|---|---|");
    for n in [32usize, 64, 128] {
        for method in [Method::Implicit, Method::Projective] {
            let frames = if n == 128 { 5 } else { 10 };
            let (ms, iters, _) = run(method, n, frames, 1, true);
            let total: f64 = ms.iter().sum::<f64>() / 1e3;
            let per = iters as f64 / frames as f64;
            let rate = match method {
                Method::Implicit => format!("{:.1}", iters as f64 / total),
                _ => "-".into(),
            };
            println!(
                "| {n}x{n} | {method:?} | 1/60 | {:.1} | {per:.1} | {rate} |",
                median(ms)
            );
        }
    }
}
