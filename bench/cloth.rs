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
//! Grids 32^2 to 256^2 (Warp's own script stops at 128^2; `cloth_warp.py` calls its
//! `run_benchmark` for 256^2 too); `implicit` with both Newton solvers (PCG, the default at
//! these sizes, and the sparse Cholesky, not run at 256^2), the per-phase time of one Newton
//! iteration at 128^2, and the chart `target/cloth_scaling.svg` (ms/frame against grid size;
//! copied to docs/mass_spring_scaling.svg). `--sizes 32,64` limits the grids; `--cg-tol`
//! compares PCG at several CG tolerances with the Cholesky's exact Newton steps instead;
//! `--stiff [--frames N]` runs issue 59's stiff sheet (1.27 m, 1 cm spacing, 1 kg) with each
//! preconditioner and writes `bench/results/cloth_stiff.json` (`stiff`).

use cgnodes::chart::{draw, Chart, Series};
use cgnodes::nodes::mesh::mesh_grid::grid_mesh;
use cgnodes::nodes::sim::mass_spring::{
    springs_from_mesh, LinearSolver, Method, Model, NewtonOptions, NewtonProfile, Preconditioner,
    QuasiNewtonOptions, Simulator, SolverOptions, SpringKinds,
};
use std::time::Instant;

#[path = "record.rs"]
mod record;

/// An `n` x `n` sheet in the xz plane with `spacing` between vertices, stretch and shear
/// springs (plus skip-one bending with `bending`) all k = 1000, `mass` per vertex, the two
/// corners of the first row fixed, gravity `g` along -y.
fn sheet(n: usize, spacing: f64, mass: f64, bending: bool, g: f64) -> (Model, Vec<[f64; 3]>) {
    let s = spacing * (n - 1) as f64;
    let mesh = grid_mesh(n - 1, n - 1, [s, s], "xz", [s / 2.0, 0.0, s / 2.0], false).unwrap();
    let kinds = SpringKinds {
        shear: true,
        bending,
        bending_scale: 1.0,
    };
    let springs = springs_from_mesh(&mesh, 1000.0, kinds);
    let nv = mesh.num_vertices();
    let mut fixed = vec![false; nv];
    fixed[0] = true;
    fixed[n - 1] = true;
    let model = Model {
        springs,
        mass: vec![mass; nv],
        fixed,
        gravity: [0.0, -g, 0.0],
        damping: 1.0,
    };
    (model, mesh.positions)
}

/// Warp's benchmark scene: 10 cm spacing, 0.1 kg per particle, bending springs.
fn warp_model(n: usize) -> (Model, Vec<[f64; 3]>) {
    sheet(n, 0.1, 0.1, true, 9.81)
}

/// Issue 59's stiff scene: a 1.27 m sheet at 128 x 128 (1 cm spacing), 1 kg in all.
fn stiff_model(n: usize) -> (Model, Vec<[f64; 3]>) {
    sheet(n, 0.01, 1.0 / (n * n) as f64, false, 9.8)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// What one benchmark run measured.
struct Run {
    /// Milliseconds per frame.
    ms: Vec<f64>,
    /// Iterations (Newton or local/global) over all steps.
    iters: usize,
    springs: usize,
    /// The implicit solver's per-phase profile.
    profile: Option<NewtonProfile>,
}

/// Runs `frames` frames of `substeps` steps, checking energy every step (as the node does,
/// for its log) or once per frame.
fn run(method: Method, n: usize, frames: usize, substeps: usize, per_step_energy: bool) -> Run {
    run_with(
        method,
        n,
        frames,
        substeps,
        per_step_energy,
        LinearSolver::Auto,
    )
}

fn run_with(
    method: Method,
    n: usize,
    frames: usize,
    substeps: usize,
    per_step_energy: bool,
    solver: LinearSolver,
) -> Run {
    let (model, x0) = warp_model(n);
    let springs = model.springs.len();
    let h = 1.0 / 60.0 / substeps as f64;
    let opts = SolverOptions {
        newton: NewtonOptions {
            solver,
            ..NewtonOptions::default()
        },
        ..SolverOptions::default()
    };
    let mut sim = Simulator::new(model, x0, None, method, h, opts).unwrap();
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
    let profile = sim.newton_profile();
    Run {
        ms,
        iters,
        springs,
        profile,
    }
}

fn warp(dims: &[usize]) -> Option<serde_json::Value> {
    if std::env::var_os("CLOTH_SKIP_WARP").is_some() {
        return None;
    }
    let py = std::env::var("CLOTH_PYTHON").unwrap_or_else(|_| "python3".into());
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/bench/peers/cloth_warp.py");
    let out = std::process::Command::new(py)
        .arg(script)
        .arg(
            dims.iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(","),
        )
        .output()
        .ok()?;
    if !out.status.success() {
        eprintln!(
            "warp benchmark failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        return None;
    }
    let text = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(text.lines().last()?).ok()
}

/// The reference 8x8 grid (spacing 0.1, k = 1000, m = 0.01, structural + shear + bending:
/// 2/omega_max = 2.0751e-3 s), released from a uniform 1 % stretch, no gravity, no damping.
fn sweep_model() -> (Model, Vec<[f64; 3]>) {
    let mesh = grid_mesh(7, 7, [0.7, 0.7], "xy", [0.35, 0.35, 0.0], false).unwrap();
    let kinds = SpringKinds {
        shear: true,
        bending: true,
        bending_scale: 1.0,
    };
    let n = mesh.num_vertices();
    let model = Model {
        springs: springs_from_mesh(&mesh, 1000.0, kinds),
        mass: vec![0.01; n],
        fixed: vec![false; n],
        gravity: [0.0; 3],
        damping: 1.0,
    };
    let x0 = mesh
        .positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            // 1 % stretch plus a small out-of-plane bump so all modes are excited.
            let z = 1e-3 * ((i * 7919) % 13) as f64 / 13.0;
            [1.01 * p[0], 1.01 * p[1], z]
        })
        .collect();
    (model, x0)
}

/// Stability and energy against time step for the three integrators over 0.2 simulated seconds
/// (at least 20 steps); writes `target/cloth_stability.svg` (copied to docs/).
fn sweep() {
    let dtc: f64 = 2.0751e-3;
    let factors = [
        0.1, 0.25, 0.5, 0.9, 0.95, 1.05, 1.5, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0,
    ];
    let methods = [Method::SemiImplicit, Method::Implicit, Method::Projective];
    println!();
    println!("Energy E(T)/E0 after T = 0.2 s (at least 20 steps) on the 8x8 grid; h in units of 2/omega_max");
    println!("| h / (2/omega_max) | semi_implicit | implicit | projective |");
    println!("|---|---|---|---|");
    let mut series: Vec<Vec<(f64, Option<f64>)>> = vec![Vec::new(); 3];
    for f in factors {
        let h = f * dtc;
        let steps = ((0.2 / h).round() as usize).max(20);
        let mut row = Vec::new();
        for (mi, &m) in methods.iter().enumerate() {
            let (model, x0) = sweep_model();
            let mut sim = Simulator::new(model, x0, None, m, h, SolverOptions::default()).unwrap();
            let e0 = sim.energy(None).total();
            let mut res = None;
            for _ in 0..steps {
                match sim.step(None) {
                    Ok(l) => res = Some(l.energy.total() / e0),
                    Err(_) => {
                        res = None;
                        break;
                    }
                }
            }
            series[mi].push((f, res));
            row.push(match res {
                Some(r) => format!("{r:.3e}"),
                None => format!("unstable (step {})", sim.steps),
            });
        }
        println!("| {f} | {} | {} | {} |", row[0], row[1], row[2]);
    }
    let svg = chart(&series, &["semi_implicit", "implicit", "projective"]);
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/target/cloth_stability.svg");
    if std::fs::write(path, svg).is_ok() {
        println!("chart: {path}");
    }
}

/// A small log-log SVG chart of E(T)/E0 against h/(2/omega_max); blow-ups drawn as crosses
/// on the top edge.
fn chart(series: &[Vec<(f64, Option<f64>)>], names: &[&str]) -> String {
    let (w, h, l, r, t, b) = (640.0, 400.0, 70.0, 150.0, 30.0, 50.0);
    let (x0, x1, y0, y1) = (
        0.1f64.log10(),
        100f64.log10(),
        1e-8f64.log10(),
        10f64.log10(),
    );
    let px = |x: f64| l + (x.log10() - x0) / (x1 - x0) * (w - l - r);
    let py = |y: f64| t + (y1 - y.max(1e-8).log10()) / (y1 - y0) * (h - t - b);
    let colors = ["#d62728", "#1f77b4", "#2ca02c"];
    let mut s = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">
<rect width="{w}" height="{h}" fill="white"/>
<text x="{}" y="18" text-anchor="middle">Energy after 0.2 s, 8x8 spring grid, against time step</text>
"#,
        (w - r + l) / 2.0
    );
    for e in (-8..=1).step_by(1) {
        let y = py(10f64.powi(e));
        s += &format!(
            "<line x1=\"{l}\" x2=\"{}\" y1=\"{y}\" y2=\"{y}\" stroke=\"#ddd\"/><text x=\"{}\" y=\"{}\" text-anchor=\"end\">1e{e}</text>\n",
            w - r,
            l - 6.0,
            y + 4.0
        );
    }
    for x in [0.1, 1.0, 10.0, 100.0] {
        let xx = px(x);
        s += &format!(
            "<line x1=\"{xx}\" x2=\"{xx}\" y1=\"{t}\" y2=\"{}\" stroke=\"#ddd\"/><text x=\"{xx}\" y=\"{}\" text-anchor=\"middle\">{x}</text>\n",
            h - b,
            h - b + 16.0
        );
    }
    s += &format!(
        "<line x1=\"{0}\" x2=\"{0}\" y1=\"{t}\" y2=\"{1}\" stroke=\"black\" stroke-dasharray=\"4 3\"/>\n",
        px(1.0),
        h - b
    );
    s += &format!(
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">h / (2 / omega_max)</text>\n<text x=\"16\" y=\"{}\" transform=\"rotate(-90 16 {})\" text-anchor=\"middle\">E(T) / E(0)</text>\n",
        (w - r + l) / 2.0,
        h - 10.0,
        (h - b + t) / 2.0,
        (h - b + t) / 2.0
    );
    for (i, ser) in series.iter().enumerate() {
        let pts: Vec<String> = ser
            .iter()
            .filter_map(|(x, y)| y.map(|y| format!("{:.1},{:.1}", px(*x), py(y))))
            .collect();
        s += &format!(
            "<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"2\" points=\"{}\"/>\n",
            colors[i],
            pts.join(" ")
        );
        for (x, y) in ser {
            let (cx, cy) = (px(*x), y.map(py).unwrap_or(t + 4.0));
            s += &match y {
                Some(_) => format!("<circle cx=\"{cx:.1}\" cy=\"{cy:.1}\" r=\"3\" fill=\"{}\"/>\n", colors[i]),
                None => format!(
                    "<text x=\"{cx:.1}\" y=\"{:.1}\" fill=\"{}\" text-anchor=\"middle\" font-size=\"14\">x</text>\n",
                    cy + 4.0,
                    colors[i]
                ),
            };
        }
        let ly = t + 20.0 + 20.0 * i as f64;
        s += &format!(
            "<line x1=\"{}\" x2=\"{}\" y1=\"{ly}\" y2=\"{ly}\" stroke=\"{}\" stroke-width=\"2\"/><text x=\"{}\" y=\"{}\">{}</text>\n",
            w - r + 10.0,
            w - r + 30.0,
            colors[i],
            w - r + 36.0,
            ly + 4.0,
            names[i]
        );
    }
    s += &format!(
        "<text x=\"{}\" y=\"{}\" font-size=\"11\">x = blew up</text>\n</svg>\n",
        w - r + 10.0,
        t + 90.0
    );
    s
}

/// The inexact Newton forcing term: PCG at several `cg_tol` against the Cholesky's exact
/// Newton steps on an n x n cloth over `frames` steps of h = 1/60.
fn cg_tol_sweep(n: usize, frames: usize) {
    let (model, x0) = warp_model(n);
    let h = 1.0 / 60.0;
    let sim = |solver: LinearSolver, cg_tol: f64| {
        let opts = SolverOptions {
            newton: NewtonOptions {
                solver,
                cg_tol,
                ..NewtonOptions::default()
            },
            ..SolverOptions::default()
        };
        let mut s =
            Simulator::new(model.clone(), x0.clone(), None, Method::Implicit, h, opts).unwrap();
        let mut xs = Vec::new();
        let mut its = Vec::new();
        let t = Instant::now();
        for _ in 0..frames {
            its.push(s.advance(None).expect("stable"));
            xs.push(s.state.x.clone());
        }
        let ms = t.elapsed().as_secs_f64() * 1e3 / frames as f64;
        (xs, its, s.newton_profile().unwrap_or_default(), ms)
    };
    let (xr, itr, _, msr) = sim(LinearSolver::Cholesky, 0.0);
    println!();
    println!("PCG forcing term on {n}x{n}, {frames} steps of h = 1/60 against the Cholesky ({msr:.1} ms/step, Newton iterations per step {itr:?})");
    println!("| cg_tol | CG iterations / Newton | Newton iterations per step | steps whose Newton count differs | max position difference | ms/step |");
    println!("|---|---|---|---|---|---|");
    for tol in [1e-2, 1e-3, 1e-4, 1e-6, 1e-8] {
        let (xs, its, p, ms) = sim(LinearSolver::Pcg, tol);
        let diff = (xs.iter().zip(&xr))
            .flat_map(|(a, b)| a.iter().zip(b))
            .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
            .fold(0.0, f64::max);
        let differ = its.iter().zip(&itr).filter(|(a, b)| a != b).count();
        println!(
            "| {tol:e} | {:.1} | {:.2} | {differ} | {diff:.1e} | {ms:.1} |",
            p.cg_iterations as f64 / p.iterations.max(1) as f64,
            its.iter().sum::<usize>() as f64 / frames as f64,
        );
    }
}

/// Per-phase milliseconds per Newton iteration (the first factorization apart).
fn phases(label: &str, p: &NewtonProfile) {
    let it = p.iterations.max(1) as f64;
    let ms = |s: f64| s * 1e3 / it;
    println!(
        "| {label} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.0} | {:.1} |",
        p.iterations,
        ms(p.gradient),
        ms(p.assemble),
        p.first_factor * 1e3,
        ms(p.factor),
        ms(p.solve),
        ms(p.line_search),
        ms(p.gradient + p.assemble + p.first_factor + p.factor + p.solve + p.line_search),
        p.cg_iterations as f64 / it,
    );
}

/// What one run of `stiff` measured, per frame.
struct Frames {
    ms: Vec<f64>,
    iterations: Vec<usize>,
    cg: Vec<usize>,
    energy: Vec<f64>,
    x: Vec<Vec<[f64; 3]>>,
}

/// `frames` steps (h = 1/60) of `scene` by `method` with `opts`, printed per frame.
fn frames_of(
    label: &str,
    (model, x0): (Model, Vec<[f64; 3]>),
    frames: usize,
    method: Method,
    opts: SolverOptions,
) -> Frames {
    let t = Instant::now();
    let mut sim = Simulator::new(model, x0, None, method, 1.0 / 60.0, opts).unwrap();
    let setup = t.elapsed().as_secs_f64() * 1e3;
    let mut last = 0;
    let mut out = Frames {
        ms: Vec::new(),
        iterations: Vec::new(),
        cg: Vec::new(),
        energy: Vec::new(),
        x: Vec::new(),
    };
    for f in 1..=frames {
        let t = Instant::now();
        let log = sim.step(None).expect("stable");
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let cg_total = sim.newton_profile().map_or(0, |p| p.cg_iterations);
        let cg = cg_total - last;
        last = cg_total;
        println!(
            "{label}: frame {f}: {ms:8.1} ms, {} iterations, {cg} CG, energy {:.6e} (set-up {setup:.1} ms)",
            log.iterations,
            log.energy.total()
        );
        out.ms.push(ms);
        out.iterations.push(log.iterations);
        out.cg.push(cg);
        out.energy.push(log.energy.total());
        out.x.push(sim.state.x.clone());
    }
    out
}

/// The largest coordinate difference between two position sets (m).
fn max_dev(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    (a.iter().zip(b))
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0, f64::max)
}

/// `--stiff`: issue 59's stiff sheet, frames 1-5: Newton with block Jacobi PCG and with
/// `Auto` (which moves to the per-axis Laplacians) at two Newton tolerances, the quasi-Newton
/// integrator (L-BFGS, Liu et al. 2017) at two tolerances, and projective dynamics at 10 and
/// 100 iterations, each with its largest distance per frame from the first run (Newton, block
/// Jacobi, 1e-7 m); then Warp's scene at 128 x 128 with block Jacobi against the per-axis
/// Laplacians outright (where they do not pay). Writes `bench/results/cloth_stiff.json`.
fn stiff(frames: usize) {
    struct Case {
        scene: &'static str,
        method: Method,
        tol: f64,
        pre: Preconditioner,
        pd_iterations: usize,
    }
    let newton = |scene, tol, pre| Case {
        scene,
        method: Method::Implicit,
        tol,
        pre,
        pd_iterations: 0,
    };
    let qn = |tol| Case {
        scene: "stiff",
        method: Method::QuasiNewton,
        tol,
        pre: Preconditioner::Auto,
        pd_iterations: 0,
    };
    let pd = |pd_iterations| Case {
        scene: "stiff",
        method: Method::Projective,
        tol: 0.0,
        pre: Preconditioner::Auto,
        pd_iterations,
    };
    let cases = [
        newton("stiff", 1e-7, Preconditioner::BlockJacobi),
        newton("stiff", 1e-7, Preconditioner::Auto),
        newton("stiff", 1e-5, Preconditioner::BlockJacobi),
        newton("stiff", 1e-5, Preconditioner::Auto),
        qn(1e-5),
        qn(1e-6),
        pd(10),
        pd(100),
        newton("warp", 1e-7, Preconditioner::BlockJacobi),
        newton("warp", 1e-7, Preconditioner::AxisLaplacians),
    ];
    let mut runs = Vec::new();
    let mut reference: Option<Vec<Vec<[f64; 3]>>> = None;
    for c in cases {
        let model = if c.scene == "stiff" {
            stiff_model(128)
        } else {
            warp_model(128)
        };
        let opts = SolverOptions {
            newton: NewtonOptions {
                solver: LinearSolver::Pcg,
                preconditioner: c.pre,
                tol: c.tol,
                ..NewtonOptions::default()
            },
            quasi_newton: QuasiNewtonOptions {
                tol: c.tol,
                ..QuasiNewtonOptions::default()
            },
            pd_iterations: c.pd_iterations.max(1),
            ..SolverOptions::default()
        };
        let label = format!(
            "{} {:?} {:?} tol {:e} pd {}",
            c.scene, c.method, c.pre, c.tol, c.pd_iterations
        );
        let r = frames_of(&label, model, frames, c.method, opts);
        let dev: Vec<f64> = match &reference {
            Some(x) if c.scene == "stiff" => {
                x.iter().zip(&r.x).map(|(a, b)| max_dev(a, b)).collect()
            }
            _ => vec![0.0; r.x.len()],
        };
        if reference.is_none() {
            reference = Some(r.x.clone());
        }
        let method = match c.method {
            Method::Implicit => "newton",
            Method::QuasiNewton => "quasi_newton",
            Method::Projective => "projective",
            Method::SemiImplicit => "semi_implicit",
        };
        runs.push(serde_json::json!({
            "scene": c.scene, "method": method, "preconditioner": format!("{:?}", c.pre),
            "newton_tol_m": c.tol, "pd_iterations": c.pd_iterations,
            "ms": r.ms, "newton": r.iterations, "cg": r.cg, "energy": r.energy,
            "max_dev_m": dev, "median_ms": median(r.ms.clone()),
        }));
    }
    let p = record::write(
        "cloth_stiff",
        &format!("cargo bench --bench cloth -- --stiff --frames {frames}"),
        serde_json::json!({ "grid": 128, "frames": frames, "h": 1.0 / 60.0,
            "stiff": { "spacing_m": 0.01, "mass_kg": 1.0, "stiffness": 1000.0 },
            "warp": { "spacing_m": 0.1, "mass_per_vertex_kg": 0.1, "stiffness": 1000.0 },
            "reference": "the first stiff run (newton, BlockJacobi, 1e-7 m)",
            "runs": runs }),
    );
    println!("wrote {}", p.display());
}

fn main() {
    if std::env::args().any(|a| a == "--sweep") {
        sweep();
        return;
    }
    let args: Vec<String> = std::env::args().collect();
    if args.iter().any(|a| a == "--stiff") {
        let frames = args
            .iter()
            .position(|a| a == "--frames")
            .and_then(|i| args.get(i + 1))
            .and_then(|f| f.parse().ok())
            .unwrap_or(5);
        stiff(frames);
        return;
    }
    if args.iter().any(|a| a == "--cg-tol") {
        cg_tol_sweep(64, 20);
        return;
    }
    let sizes: Vec<usize> = args
        .iter()
        .position(|a| a == "--sizes")
        .and_then(|i| args.get(i + 1))
        .map(|s| s.split(',').filter_map(|t| t.parse().ok()).collect())
        .unwrap_or_else(|| vec![32, 64, 128, 256]);
    let threads = rayon::current_num_threads();
    println!("cgnodes mass_spring, {threads} rayon threads; Warp CPU cloth benchmark settings");
    let w = warp(&sizes);
    if let Some(w) = &w {
        println!("warp-lang {}", w["version"]);
    }
    let warp_min = |n: usize| w.as_ref().and_then(|w| w[n.to_string()]["min"].as_f64());
    let f = |x: Option<f64>| x.map(|x| format!("{x:.2}")).unwrap_or("-".into());
    println!(
        "| grid | springs | semi_implicit ms/frame, energy per frame (per step) | same, 1 thread | warp ms/frame (min / avg) | warp min / cgnodes 1 thread |"
    );
    println!("|---|---|---|---|---|---|");
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut chart = vec![Vec::new(); 5];
    for &n in &sizes {
        let frames = if n >= 256 { 20 } else { 60 };
        let r = run(Method::SemiImplicit, n, frames, 16, false);
        let (pool, springs) = (median(r.ms), r.springs);
        let ours = median(
            one.install(|| run(Method::SemiImplicit, n, frames, 16, false))
                .ms,
        );
        let logged = median(run(Method::SemiImplicit, n, frames, 16, true).ms);
        let wmin = warp_min(n);
        let wavg = w.as_ref().and_then(|w| w[n.to_string()]["avg"].as_f64());
        let ratio = wmin
            .map(|m| format!("{:.2}", m / ours))
            .unwrap_or("-".into());
        println!(
            "| {n}x{n} | {springs} | {pool:.2} ({logged:.2}) | {ours:.2} | {} / {} | {ratio} |",
            f(wmin),
            f(wavg)
        );
        chart[0].push((n as f64, pool));
        if let Some(m) = wmin {
            chart[4].push((n as f64, m));
        }
    }
    println!();
    println!("One backward Euler step per frame (h = 1/60), energy checked every step; implicit: Newton to 1e-7");
    println!("| grid | integrator | ms/frame (median) | iterations/step | CG iterations/Newton | ms/Newton iteration | warp min / cgnodes |");
    println!("|---|---|---|---|---|---|---|");
    let mut profiles = Vec::new();
    for &n in &sizes {
        let cases = [
            (Method::Implicit, LinearSolver::Pcg, "implicit (PCG)", 1),
            (
                Method::Implicit,
                LinearSolver::Cholesky,
                "implicit (Cholesky)",
                2,
            ),
            (Method::Projective, LinearSolver::Auto, "projective", 3),
        ];
        for (method, solver, label, series) in cases {
            if solver == LinearSolver::Cholesky && n > 128 {
                println!("| {n}x{n} | {label} | not run (2D factorization flops grow ~8x per doubling of n) | | | | |");
                continue;
            }
            let frames = match (n, solver) {
                (128, LinearSolver::Cholesky) => 3,
                (256.., _) => 5,
                _ => 10,
            };
            let r = run_with(method, n, frames, 1, true, solver);
            let total: f64 = r.ms.iter().sum();
            let per = r.iters as f64 / frames as f64;
            let med = median(r.ms.clone());
            let (cg, per_newton) = match &r.profile {
                Some(p) => (
                    format!("{:.1}", p.cg_iterations as f64 / p.iterations.max(1) as f64),
                    format!("{:.1}", total / r.iters.max(1) as f64),
                ),
                None => ("-".into(), "-".into()),
            };
            let ratio = warp_min(n)
                .map(|m| format!("{:.3}", m / med))
                .unwrap_or("-".into());
            println!("| {n}x{n} | {label} | {med:.1} | {per:.1} | {cg} | {per_newton} | {ratio} |");
            chart[series].push((n as f64, med));
            if n == 128 {
                if let Some(p) = r.profile {
                    profiles.push((label, p));
                }
            }
        }
    }
    if !profiles.is_empty() {
        println!();
        println!("Implicit at 128x128, ms per Newton iteration by phase (first factorization: total ms, once)");
        println!("| solver | Newton iterations | gradient | Hessian | first factorization (symbolic + numeric) | numeric factorization | solve (CG or triangular) | line search | total | CG iterations |");
        println!("|---|---|---|---|---|---|---|---|---|---|");
        for (label, p) in &profiles {
            phases(label, p);
        }
    }
    let names = [
        "semi_implicit (16 substeps)",
        "implicit, PCG (1 step)",
        "implicit, Cholesky (1 step)",
        "projective (1 step)",
        "Warp CPU (16 substeps)",
    ];
    let c = Chart {
        title: format!("Cloth ms/frame against grid size ({threads} threads, 60 fps frames)"),
        x_label: "grid side n (n x n vertices)".into(),
        y_label: "ms per frame (median)".into(),
        series: (names.iter().zip(chart))
            .filter(|(_, p)| !p.is_empty())
            .map(|(l, points)| Series {
                label: l.to_string(),
                points,
            })
            .collect(),
        failures: Vec::new(),
        log_x: true,
        log_y: true,
    };
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/target/cloth_scaling.svg");
    match draw(&c, std::path::Path::new(path)) {
        Ok(()) => println!("chart: {path}"),
        Err(e) => eprintln!("chart: {e}"),
    }
}
