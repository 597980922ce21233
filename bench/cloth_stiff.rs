//! Stiff cloth at a real size (issue 59): a 1.27 m square sheet of 128 x 128 vertices (1 cm
//! spacing) in the xz plane, total mass 1 kg, stretch and shear springs k = 1000, the two
//! corners of its first row fixed, gravity -9.8 along y, one backward Euler step of h = 1/60
//! per frame. Prints ms per frame, Newton and CG iterations, and the energy, for frames 1-5.
//! `cargo bench --bench cloth_stiff -- [--frames N] [--n N] [--solver pcg|cholesky]
//! [--precond auto|jacobi|axes] [--newton-tol METRES]`; prints the median of the frames too.
//! `--record` instead runs block Jacobi and `Auto` (which moves to the per-axis Laplacians)
//! one after the other at two Newton tolerances, and writes `bench/results/cloth_stiff.json`.

#[path = "record.rs"]
mod record;

use cgnodes::nodes::mesh::mesh_grid::grid_mesh;
use cgnodes::nodes::sim::mass_spring::{
    springs_from_mesh, LinearSolver, Method, Model, NewtonOptions, Preconditioner, Simulator,
    SolverOptions, SpringKinds,
};
use std::time::Instant;

/// The stiff scene at `n` x `n` vertices.
pub fn stiff_model(n: usize) -> (Model, Vec<[f64; 3]>) {
    let s = 0.01 * (n - 1) as f64;
    let mesh = grid_mesh(n - 1, n - 1, [s, s], "xz", [s / 2.0, 0.0, s / 2.0], false).unwrap();
    let kinds = SpringKinds {
        shear: true,
        bending: false,
        bending_scale: 1.0,
    };
    let springs = springs_from_mesh(&mesh, 1000.0, kinds);
    let nv = mesh.num_vertices();
    let mut fixed = vec![false; nv];
    fixed[0] = true;
    fixed[n - 1] = true;
    let model = Model {
        springs,
        mass: vec![1.0 / nv as f64; nv],
        fixed,
        gravity: [0.0, -9.8, 0.0],
        damping: 1.0,
    };
    (model, mesh.positions)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |k: &str| {
        args.iter()
            .position(|a| a == k)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let frames: usize = arg("--frames").and_then(|s| s.parse().ok()).unwrap_or(5);
    let n: usize = arg("--n").and_then(|s| s.parse().ok()).unwrap_or(128);
    let solver = match arg("--solver").as_deref() {
        Some("cholesky") => LinearSolver::Cholesky,
        Some("pcg") => LinearSolver::Pcg,
        _ => LinearSolver::Auto,
    };
    let preconditioner = match arg("--precond").as_deref() {
        Some("jacobi") => Preconditioner::BlockJacobi,
        Some("axes") => Preconditioner::AxisLaplacians,
        _ => Preconditioner::Auto,
    };
    let tol: f64 = arg("--newton-tol")
        .and_then(|s| s.parse().ok())
        .unwrap_or(NewtonOptions::default().tol);
    if args.iter().any(|a| a == "--record") {
        let mut runs = Vec::new();
        for tol in [1e-7, 1e-5] {
            for pre in [Preconditioner::BlockJacobi, Preconditioner::Auto] {
                let r = simulate(n, frames, solver, pre, tol);
                runs.push(serde_json::json!({
                    "preconditioner": format!("{pre:?}"), "newton_tol_m": tol,
                    "ms": r.ms, "newton": r.newton, "cg": r.cg, "energy": r.energy,
                    "median_ms": median(&r.ms),
                }));
            }
        }
        let p = record::write(
            "cloth_stiff",
            &format!("cargo bench --bench cloth_stiff -- --record --frames {frames}"),
            serde_json::json!({ "grid": n, "frames": frames, "h": 1.0 / 60.0,
                                "spacing_m": 0.01, "mass_kg": 1.0, "stiffness": 1000.0,
                                "runs": runs }),
        );
        println!("wrote {}", p.display());
        return;
    }
    let r = simulate(n, frames, solver, preconditioner, tol);
    println!(
        "median {:.1} ms/frame ({preconditioner:?}, Newton tol {tol:e} m)",
        median(&r.ms)
    );
}

/// What one simulation measured, per frame.
struct Frames {
    ms: Vec<f64>,
    newton: Vec<usize>,
    cg: Vec<usize>,
    energy: Vec<f64>,
}

fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Runs `frames` steps of the stiff scene and prints each.
fn simulate(
    n: usize,
    frames: usize,
    solver: LinearSolver,
    preconditioner: Preconditioner,
    tol: f64,
) -> Frames {
    let (model, x0) = stiff_model(n);
    let opts = SolverOptions {
        newton: NewtonOptions {
            solver,
            preconditioner,
            tol,
            ..NewtonOptions::default()
        },
        ..SolverOptions::default()
    };
    let mut sim = Simulator::new(model, x0, None, Method::Implicit, 1.0 / 60.0, opts).unwrap();
    let mut last = sim.newton_profile().unwrap_or_default();
    let mut out = Frames {
        ms: Vec::new(),
        newton: Vec::new(),
        cg: Vec::new(),
        energy: Vec::new(),
    };
    for f in 1..=frames {
        let t = Instant::now();
        let log = sim.step(None).expect("stable");
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let p = sim.newton_profile().unwrap_or_default();
        let cg = p.cg_iterations - last.cg_iterations;
        println!(
            "{preconditioner:?} tol {tol:e}: frame {f}: {ms:8.1} ms, {} Newton, {cg} CG, energy {:.6e}",
            log.iterations,
            log.energy.total()
        );
        last = p;
        out.ms.push(ms);
        out.newton.push(log.iterations);
        out.cg.push(cg);
        out.energy.push(log.energy.total());
    }
    out
}
