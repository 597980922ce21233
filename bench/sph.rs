//! SPH benchmark beside SPlisHSPlasH on the 2-D Martin & Moyce dam break (column a x 2a,
//! a = 0.5 m, tank 4a x 2.5a, to T = 3.5): particle-steps per second and the time-anchored
//! front error, for several particle radii, in the same run. Writes
//! `docs/sph_front_error.svg` (front error against time) and `docs/sph_bench.csv`.
//!
//! `cargo bench --bench sph` (radii from `SPH_RADII`, default `0.01,0.005`). The peer runs
//! through `bench/peers/sph_splishsplash.py` with the Python in `SPH_PEER_PYTHON` (default
//! `python3`; needs `pip install pysplishsplash`); it is skipped if that fails.

#[path = "../tests/it/support/sph_dam_break.rs"]
mod dam_break;

use cgnodes::nodes::sim::sph::Solver;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

struct Run {
    name: String,
    r: f64,
    particles: usize,
    steps: usize,
    seconds: f64,
    errors: Vec<(f64, f64)>,
}

const T_END: f64 = 3.5;

fn ours(solver: Solver, r: f64, exp: &[(f64, f64)]) -> Run {
    let mut f = dam_break::setup(solver, 0.5, r, 1e-4).unwrap();
    let t0 = Instant::now();
    let sim = dam_break::run(&mut f, T_END, 0.005).unwrap();
    let seconds = t0.elapsed().as_secs_f64();
    Run {
        name: format!("cgnodes {solver:?}")
            .to_uppercase()
            .replace("CGNODES", "cgnodes"),
        r,
        particles: f.len(),
        steps: f.steps,
        seconds,
        errors: dam_break::anchored_errors(&sim, exp),
    }
}

fn peer(r: f64, exp: &[(f64, f64)], root: &Path) -> Option<Run> {
    let py = std::env::var("SPH_PEER_PYTHON").unwrap_or_else(|_| "python3".into());
    let out = std::process::Command::new(py)
        .arg(root.join("bench/peers/sph_splishsplash.py"))
        .arg(r.to_string())
        .arg(T_END.to_string())
        .env("LD_PRELOAD", "/lib/x86_64-linux-gnu/libGLdispatch.so.0")
        // OpenMP spin-waiting collapses on a shared machine; passive waiting is fair.
        .env("OMP_WAIT_POLICY", "PASSIVE")
        .output()
        .ok()?;
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text.lines().find(|l| l.starts_with('{'))?;
    let j: serde_json::Value = serde_json::from_str(line).ok()?;
    let front: Vec<(f64, f64)> = j["front"]
        .as_array()?
        .iter()
        .filter_map(|p| Some((p[0].as_f64()?, p[1].as_f64()?)))
        .collect();
    Some(Run {
        name: "SPlisHSPlasH DFSPH".into(),
        r,
        particles: j["particles"].as_u64()? as usize,
        steps: j["steps"].as_u64()? as usize,
        seconds: j["seconds"].as_f64()?,
        errors: dam_break::anchored_errors(&front, exp),
    })
}

fn svg(runs: &[Run]) -> String {
    let (w, h, l, b) = (640.0, 400.0, 60.0, 40.0);
    let (tmin, tmax, emin, emax) = (1.0, 3.6, -0.1, 0.1);
    let px = |t: f64| l + (t - tmin) / (tmax - tmin) * (w - l - 20.0);
    let py = |e: f64| 20.0 + (emax - e.clamp(emin, emax)) / (emax - emin) * (h - b - 20.0);
    let mut s = format!(
        "<svg xmlns='http://www.w3.org/2000/svg' width='{w}' height='{h}' font-family='sans-serif' font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n"
    );
    for e in [-0.1, -0.05, 0.0, 0.05, 0.1] {
        let _ = writeln!(s, "<line x1='{l}' x2='{}' y1='{y}' y2='{y}' stroke='#ddd'/><text x='5' y='{}'>{:+.0} %</text>", w - 20.0, py(e) + 4.0, e * 100.0, y = py(e));
    }
    for t in [1.0, 1.5, 2.0, 2.5, 3.0, 3.5] {
        let _ = writeln!(
            s,
            "<text x='{}' y='{}'>{t}</text>",
            px(t) - 8.0,
            h - b + 16.0
        );
    }
    let _ = writeln!(s, "<text x='{}' y='{}'>T = t sqrt(2g/a) (experiment)</text><text x='{l}' y='14'>front error (T_sim - T_exp) / T_exp, anchored at T = 1.19, Z = 1.44</text>", w / 2.0 - 80.0, h - 6.0);
    let colors = [
        "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#17becf", "#7f7f7f",
    ];
    for (k, run) in runs.iter().enumerate() {
        let c = colors[k % colors.len()];
        let pts: Vec<String> = run
            .errors
            .iter()
            .map(|(t, e)| format!("{:.1},{:.1}", px(*t), py(*e)))
            .collect();
        let _ = writeln!(
            s,
            "<polyline fill='none' stroke='{c}' stroke-width='1.5' points='{}'/>",
            pts.join(" ")
        );
        let _ = writeln!(
            s,
            "<text x='{}' y='{}' fill='{c}'>{} r = {} ({} particles)</text>",
            w - 300.0,
            h - b - 10.0 - 14.0 * k as f64,
            run.name,
            run.r,
            run.particles
        );
    }
    s.push_str("</svg>\n");
    s
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let exp = dam_break::martin_moyce_front();
    let radii: Vec<f64> = std::env::var("SPH_RADII")
        .unwrap_or_else(|_| "0.01,0.005".into())
        .split(',')
        .filter_map(|x| x.trim().parse().ok())
        .collect();
    let mut runs = Vec::new();
    for &r in &radii {
        runs.push(ours(Solver::Dfsph, r, &exp));
        if r >= 0.005 {
            runs.push(ours(Solver::Wcsph, r, &exp));
        }
        match peer(r, &exp, root) {
            Some(p) => runs.push(p),
            None => eprintln!("SPlisHSPlasH peer unavailable (set SPH_PEER_PYTHON)"),
        }
    }
    println!(
        "| solver | r | particles | steps | s | particle-steps/s | front error (RMS rel. in T) |"
    );
    println!("|---|---|---|---|---|---|---|");
    let mut csv =
        String::from("solver,r,particles,steps,seconds,particle_steps_per_s,front_error\n");
    for run in &runs {
        let ps = run.particles as f64 * run.steps as f64 / run.seconds;
        let e = dam_break::rms(&run.errors);
        println!(
            "| {} | {} | {} | {} | {:.2} | {:.2} M | {:.1} % |",
            run.name,
            run.r,
            run.particles,
            run.steps,
            run.seconds,
            ps / 1e6,
            e * 100.0
        );
        let _ = writeln!(
            csv,
            "{},{},{},{},{:.3},{:.0},{:.4}",
            run.name, run.r, run.particles, run.steps, run.seconds, ps, e
        );
    }
    let docs = root.join("docs");
    let _ = std::fs::create_dir_all(&docs);
    std::fs::write(docs.join("sph_front_error.svg"), svg(&runs)).unwrap();
    std::fs::write(docs.join("sph_bench.csv"), csv).unwrap();
}
