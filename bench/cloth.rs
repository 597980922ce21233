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

use cgnodes::nodes::mesh::mesh_grid::grid_mesh;
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

fn main() {
    if std::env::args().any(|a| a == "--sweep") {
        sweep();
        return;
    }
    let threads = rayon::current_num_threads();
    println!("cgnodes mass_spring, {threads} rayon threads; Warp CPU cloth benchmark settings");
    let w = warp();
    if let Some(w) = &w {
        println!("warp-lang {}", w["version"]);
    }
    println!(
        "| grid | springs | semi_implicit ms/frame, energy per frame (per step) | same, 1 thread | warp ms/frame (min / avg) | warp min / cgnodes 1 thread |"
    );
    println!("|---|---|---|---|---|---|");
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    for n in [32usize, 64, 128] {
        let (ms, _, springs) = run(Method::SemiImplicit, n, 60, 16, false);
        let pool = median(ms);
        let ours = median(
            one.install(|| run(Method::SemiImplicit, n, 60, 16, false))
                .0,
        );
        let logged = median(run(Method::SemiImplicit, n, 60, 16, true).0);
        let (wmin, wavg) = w
            .as_ref()
            .map(|w| {
                (
                    w[n.to_string()]["min"].as_f64(),
                    w[n.to_string()]["avg"].as_f64(),
                )
            })
            .unwrap_or((None, None));
        let f = |x: Option<f64>| x.map(|x| format!("{x:.2}")).unwrap_or("-".into());
        let ratio = wmin
            .map(|m| format!("{:.2}", m / ours))
            .unwrap_or("-".into());
        println!(
            "| {n}x{n} | {springs} | {pool:.2} ({logged:.2}) | {ours:.2} | {} / {} | {ratio} |",
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
