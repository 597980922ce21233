//! ARAP parameterization beside libigl, in the same run.
//!
//! `cargo bench --bench arap [-- ITERATIONS [MESH.obj ...]]` (default 100 iterations, the
//! `arap` node's default, on camel_b, camelhead, nefertiti_front, bunny_base, bunny_open (the
//! hard inputs of issue 29, `bench/peers/arap_meshes.py`) and igea_front; the fold-free
//! mode front-loads its refactorizations, so its time per iteration depends on the run length:
//! `-- 30` is the shorter run measured in `docs/arap.md`). For each mesh: ours plain and
//! fold-free from the default Tutte start (mean-value weights, circle), and libigl's
//! `arap_solve` from `igl.harmonic` with one pinned vertex (`bench/peers/arap_libigl.py`, needs
//! `pip install libigl`). Ours are measured with `uv_metrics`, libigl's with the same definition
//! in numpy (UV area scaled to the 3-D area, flips against the majority); both agree where the
//! vertex orders can be matched by position. Time per iteration excludes setup
//! (our frames and factorization; libigl's precomputation), which is reported separately.
//! Writes `target/bench/arap/*.csv` (energy against time) and `docs/arap_energy_time.svg`.
//! `ARAP_REFACTOR=PER_ITERATION,BLOCKED_RUN,GROWTH` overrides the fold-free mode's refactor
//! schedule (`RefactorSchedule`; `3,0,0` refactors on every blocked round, as before the schedule);
//! `ARAP_LOCAL_RINGS=0` turns off the local stiffened re-solves (`ArapOptions::local_rings`).
//!
//! The machine's speed drifts by tens of percent from minute to minute, so each mesh is run
//! `ARAP_BENCH_RUNS` times (default 5), ours and libigl's in turn within each round, and the
//! time per iteration reported is each method's median over the rounds; the table also gives
//! the range of the per-round ratios. Energies, flips and curves come from the first round
//! (both methods are deterministic).

use cgnodes::nodes::mesh::obj::load_obj;
use cgnodes::nodes::param::arap::{
    arap_parameterize, ArapOptions, ArapResult, RefactorSchedule, LOG_COLUMNS,
};
use cgnodes::nodes::param::tutte::{tutte_parameterize, BoundaryShape, TutteWeights};
use cgnodes::nodes::param::uv_metrics::uv_metrics;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;
use std::time::Instant;

/// One energy-against-time curve.
struct Curve {
    label: String,
    points: Vec<(f64, f64)>,
}

/// One method's outcome on one mesh.
struct Outcome {
    setup_ms: f64,
    iter_ms: f64,
    /// Time per iteration in each round (`ARAP_BENCH_RUNS`), the first being `iter_ms`'s run.
    samples: Vec<f64>,
    energy: f64,
    flips: usize,
    refactors: Option<(usize, usize)>,
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let iterations: usize = args
        .first()
        .and_then(|a| a.parse().ok())
        .unwrap_or(ArapOptions::default().iterations);
    let mut meshes: Vec<PathBuf> = args.iter().skip(1).map(PathBuf::from).collect();
    if meshes.is_empty() {
        meshes = vec![
            root.join("assets/meshes/camel_b.obj"),
            root.join("assets/meshes/camelhead.obj"),
            root.join("assets/meshes/nefertiti_front.obj"),
            root.join("assets/meshes/bunny_base.obj"),
            root.join("assets/meshes/bunny_open.obj"),
            root.join("assets/meshes/igea_front.obj"),
        ];
    }
    let out_dir = root.join("target/bench/arap");
    std::fs::create_dir_all(&out_dir).expect("create target/bench/arap");
    let mut seen = std::collections::BTreeSet::new();
    let mut table = String::from(
        "| mesh (faces) | method | setup ms | ms / iteration (median) | ratio to libigl (per-round range) | ARAP E | flips | refactors (local re-solves) |\n|---|---|---|---|---|---|---|---|\n",
    );
    let mut chart_curves: Vec<(String, Vec<Curve>)> = Vec::new();
    for path in meshes {
        let Some(name) = path.file_stem().map(|s| s.to_string_lossy().to_string()) else {
            continue;
        };
        if !path.exists() || !seen.insert(name.clone()) {
            continue;
        }
        let mesh = Arc::new(load_obj(&path, "").expect("load mesh")).triangulated();
        let tris = mesh.triangles().expect("triangles");
        eprintln!("{name}: {} faces", tris.len());

        let t0 = Instant::now();
        let init = tutte_parameterize(&mesh, TutteWeights::MeanValue, BoundaryShape::Circle, true)
            .expect("tutte");
        let tutte_ms = t0.elapsed().as_secs_f64() * 1e3;
        let m0 = uv_metrics(&mesh.positions, &tris, &init);

        let mut curves = Vec::new();
        let mut ours = Vec::new();
        let local_rings = std::env::var("ARAP_LOCAL_RINGS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(ArapOptions::default().local_rings);
        let options = |injective| ArapOptions {
            iterations,
            tolerance: 0.0,
            injective,
            refactor: schedule(),
            local_rings,
            ..Default::default()
        };
        for injective in [false, true] {
            let opts = options(injective);
            let r = arap_parameterize(&mesh.positions, &tris, &init, &opts).expect("arap");
            let m = uv_metrics(&mesh.positions, &tris, &r.uv);
            let label = if injective {
                "ours, fold-free"
            } else {
                "ours, plain"
            };
            curves.push(curve(label, &r, tutte_ms));
            let mut o = outcome(&r, m.arap_energy, m.flipped + m.collapsed);
            o.refactors = Some((r.refactors, r.local_solves));
            eprintln!(
                "{name} {label}: {} iterations, stop {} {}, {} refactors, {} local re-solves, {} reweighted, {} collapsed",
                r.log.len() - 1,
                r.stop_reason.as_str(),
                r.stop_detail,
                r.refactors,
                r.local_solves,
                r.reweighted,
                m.collapsed
            );
            ours.push((label, o));
            write_csv(
                &out_dir.join(format!("{name}_{}.csv", label.replace([',', ' '], ""))),
                &r,
            );
        }

        let prefix = out_dir.join(format!("{name}_libigl"));
        let igl = run_libigl(root, &path, iterations, &prefix, &mesh.positions);
        let mut igl_outcome = igl.as_ref().map(|(json, uv)| {
            let m = uv_metrics(&mesh.positions, &tris, uv);
            let log = json["log"].as_array().cloned().unwrap_or_default();
            let harmonic_ms = json["harmonic_ms"].as_f64().unwrap_or(0.0);
            let pre = json["precompute_ms"].as_f64().unwrap_or(0.0);
            curves.push(Curve {
                label: "libigl".into(),
                points: log
                    .iter()
                    .map(|r| {
                        (
                            harmonic_ms + pre + r["elapsed_ms"].as_f64().unwrap_or(0.0),
                            r["energy_raw"].as_f64().unwrap_or(f64::NAN),
                        )
                    })
                    .collect(),
            });
            // libigl's own final row (same definition, computed in numpy); our metric on its
            // UVs when the vertex matching is complete (duplicate positions defeat it)
            let last = log.last().cloned().unwrap_or_default();
            let matched = uv.iter().all(|p| p[0].is_finite());
            if matched {
                eprintln!(
                    "{name}: libigl by uv_metrics: E {:.4}, flips {}",
                    m.arap_energy,
                    m.flipped + m.collapsed
                );
            }
            Outcome {
                setup_ms: pre,
                iter_ms: json["iteration_ms"].as_f64().unwrap_or(f64::NAN),
                energy: last["energy"].as_f64().unwrap_or(f64::NAN),
                flips: last["flips"].as_u64().unwrap_or(0) as usize,
                refactors: None,
                samples: Vec::new(),
            }
        });
        // further rounds, ours and libigl's in turn (see the module docs)
        let runs: usize = std::env::var("ARAP_BENCH_RUNS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(5);
        for o in ours.iter_mut().map(|(_, o)| o) {
            o.samples.push(o.iter_ms);
        }
        if let Some(g) = igl_outcome.as_mut() {
            g.samples.push(g.iter_ms);
        }
        for _ in 1..runs {
            for (k, injective) in [false, true].into_iter().enumerate() {
                let opts = options(injective);
                let r = arap_parameterize(&mesh.positions, &tris, &init, &opts).expect("arap");
                let t = outcome(&r, 0.0, 0).iter_ms;
                ours[k].1.samples.push(t);
            }
            if let Some(g) = igl_outcome.as_mut() {
                let rep_prefix = out_dir.join(format!("{name}_libigl_rerun"));
                // a failed rerun records NaN, keeping the rounds aligned (median skips it)
                let t = run_libigl_script(root, &path, iterations, &rep_prefix)
                    .and_then(|json| json["iteration_ms"].as_f64());
                g.samples.push(t.unwrap_or(f64::NAN));
            }
        }
        for o in ours.iter_mut().map(|(_, o)| o) {
            o.iter_ms = median(&o.samples);
        }
        if let Some(g) = igl_outcome.as_mut() {
            g.iter_ms = median(&g.samples);
        }
        let _ = writeln!(
            table,
            "| {name} ({}) | start: Tutte mean-value | {tutte_ms:.0} | | | {:.4} | {} | |",
            tris.len(),
            m0.arap_energy,
            m0.flipped
        );
        for (label, o) in &ours {
            let ratio = igl_outcome.as_ref().map_or("n/a".to_string(), |g| {
                let per_round: Vec<f64> = o
                    .samples
                    .iter()
                    .zip(&g.samples)
                    .map(|(a, b)| a / b)
                    .collect();
                let lo = per_round.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = per_round.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                format!("{:.2} ({lo:.2}-{hi:.2})", o.iter_ms / g.iter_ms)
            });
            let _ = writeln!(
                table,
                "| {name} | {label} | {:.0} | {:.2} | {ratio} | {:.4} | {} | {} |",
                o.setup_ms,
                o.iter_ms,
                o.energy,
                o.flips,
                o.refactors
                    .map_or(String::new(), |(r, l)| format!("{r} ({l})"))
            );
        }
        match &igl_outcome {
            Some(g) => {
                let _ = writeln!(
                    table,
                    "| {name} | libigl (from harmonic) | {:.0} | {:.2} | 1 | {:.4} | {} | |",
                    g.setup_ms, g.iter_ms, g.energy, g.flips
                );
            }
            None => {
                let _ = writeln!(table, "| {name} | libigl | not available | | | | | |");
            }
        }
        chart_curves.push((format!("{name} ({} faces)", tris.len()), curves));
    }
    println!("\n{iterations} iterations each, tolerance 0\n\n{table}");
    let svg = chart(&chart_curves);
    let svg_path = root.join("docs/arap_energy_time.svg");
    if std::fs::create_dir_all(root.join("docs")).is_ok() && std::fs::write(&svg_path, svg).is_ok()
    {
        eprintln!("chart: {}", svg_path.display());
    }
}

fn outcome(r: &ArapResult, energy: f64, flips: usize) -> Outcome {
    let n = (r.log.len() - 1).max(1) as f64;
    let first = r.log[0].elapsed_ms;
    let last = r.log.last().map_or(first, |x| x.elapsed_ms);
    Outcome {
        setup_ms: first,
        iter_ms: (last - first) / n,
        energy,
        flips,
        refactors: None,
        samples: Vec::new(),
    }
}

/// The median of the samples that are not NaN.
fn median(v: &[f64]) -> f64 {
    let mut v: Vec<f64> = v.iter().copied().filter(|x| !x.is_nan()).collect();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// Runs `bench/peers/arap_libigl.py` and reads the JSON it writes at `prefix` (`None` if the
/// peer failed).
fn run_libigl_script(
    root: &Path,
    mesh: &Path,
    iterations: usize,
    prefix: &Path,
) -> Option<serde_json::Value> {
    let status = Command::new("python3")
        .arg(root.join("bench/peers/arap_libigl.py"))
        .arg(mesh)
        .arg(iterations.to_string())
        .arg(prefix)
        .status();
    if !matches!(status, Ok(s) if s.success()) {
        return None;
    }
    serde_json::from_slice(&std::fs::read(prefix.with_extension("json")).ok()?).ok()
}

/// The refactor schedule, from `ARAP_REFACTOR` if set.
fn schedule() -> RefactorSchedule {
    let d = RefactorSchedule::default();
    let Ok(v) = std::env::var("ARAP_REFACTOR") else {
        return d;
    };
    let f: Vec<&str> = v.split(',').collect();
    let get = |i: usize| f.get(i).and_then(|x| x.trim().parse::<f64>().ok());
    RefactorSchedule {
        per_iteration: get(0).map_or(d.per_iteration, |x| x as usize),
        blocked_run: get(1).map_or(d.blocked_run, |x| x as usize),
        growth: get(2).unwrap_or(d.growth),
    }
}

fn curve(label: &str, r: &ArapResult, offset_ms: f64) -> Curve {
    Curve {
        label: label.into(),
        points: r
            .log
            .iter()
            .map(|x| (offset_ms + x.elapsed_ms, x.energy))
            .collect(),
    }
}

fn write_csv(path: &Path, r: &ArapResult) {
    let rows = r.log.iter().map(|x| {
        vec![
            x.iteration.to_string(),
            x.energy.to_string(),
            x.flips.to_string(),
            x.elapsed_ms.to_string(),
            x.step.to_string(),
            u8::from(x.blocked).to_string(),
            x.refactors.to_string(),
        ]
    });
    let header = std::iter::once(LOG_COLUMNS.map(String::from).to_vec());
    let _ = std::fs::write(path, cgnodes::io::csv::to_text(header.chain(rows)));
}

/// Runs the libigl peer; `None` (with a note) when Python or libigl is missing.
fn run_libigl(
    root: &Path,
    mesh: &Path,
    iterations: usize,
    prefix: &Path,
    positions: &[[f64; 3]],
) -> Option<(serde_json::Value, Vec<[f64; 2]>)> {
    let Some(json) = run_libigl_script(root, mesh, iterations, prefix) else {
        eprintln!("libigl peer failed or missing (pip install libigl)");
        return None;
    };
    let f64s = |ext: &str| -> Option<Vec<f64>> {
        let bytes = std::fs::read(prefix.with_extension(ext)).ok()?;
        Some(
            bytes
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
                .collect(),
        )
    };
    let (uv, v) = (f64s("uv")?, f64s("v")?);
    // libigl keeps the file's vertex order, our OBJ loader numbers vertices by first use:
    // match them by position (as f32, the precision our loader reads).
    let key = |p: &[f64]| {
        p.iter()
            .map(|x| (*x as f32).to_bits())
            .collect::<Vec<u32>>()
    };
    let mut index = std::collections::HashMap::new();
    for (j, p) in v.chunks_exact(3).enumerate() {
        index.entry(key(p)).or_insert(j);
    }
    let ours: Vec<[f64; 2]> = positions
        .iter()
        .map(|p| {
            index
                .get(&key(p))
                .map_or([f64::NAN; 2], |&j| [uv[2 * j], uv[2 * j + 1]])
        })
        .collect();
    Some((json, ours))
}

/// Energy against time, one panel per mesh, log-scale energy, as plain SVG.
fn chart(panels: &[(String, Vec<Curve>)]) -> String {
    let (pw, ph, margin) = (420.0, 300.0, 55.0);
    let cols = 2usize;
    let rows = panels.len().div_ceil(cols).max(1);
    let (w, h) = (
        cols as f64 * (pw + margin) + margin,
        rows as f64 * (ph + margin) + margin + 30.0,
    );
    let colors = ["#1f77b4", "#2ca02c", "#d62728"];
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"{margin}\" y=\"22\" font-size=\"15\">ARAP energy (as minimized, UVs unscaled) against time in ms, from the start of the initialization</text>\n"
    );
    for (k, (title, curves)) in panels.iter().enumerate() {
        let x0 = margin + (k % cols) as f64 * (pw + margin);
        let y0 = 40.0 + margin * 0.5 + (k / cols) as f64 * (ph + margin);
        let pts: Vec<(f64, f64)> = curves
            .iter()
            .flat_map(|c| c.points.iter().copied())
            .filter(|p| p.0.is_finite() && p.1 > 0.0 && p.1.is_finite())
            .collect();
        if pts.is_empty() {
            continue;
        }
        let tmax = pts.iter().map(|p| p.0).fold(0.0, f64::max).max(1e-9);
        let lo = pts
            .iter()
            .map(|p| p.1.log10())
            .fold(f64::INFINITY, f64::min)
            .floor();
        let hi = pts
            .iter()
            .map(|p| p.1.log10())
            .fold(f64::NEG_INFINITY, f64::max)
            .ceil()
            .max(lo + 1.0);
        let px = |t: f64| x0 + t / tmax * pw;
        let py = |e: f64| y0 + ph - (e.log10() - lo) / (hi - lo) * ph;
        let _ = writeln!(
            s,
            "<rect x=\"{x0}\" y=\"{y0}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"#888\"/>\n<text x=\"{}\" y=\"{}\">{title}</text>",
            x0 + 5.0,
            y0 - 6.0
        );
        let mut d = lo;
        while d <= hi + 1e-9 {
            let y = py(10f64.powf(d));
            let _ = writeln!(
                s,
                "<line x1=\"{x0}\" x2=\"{}\" y1=\"{y}\" y2=\"{y}\" stroke=\"#eee\"/><text x=\"{}\" y=\"{}\" text-anchor=\"end\">1e{d}</text>",
                x0 + pw,
                x0 - 4.0,
                y + 4.0
            );
            d += 1.0;
        }
        for f in [0.0, 0.5, 1.0] {
            let _ = writeln!(
                s,
                "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{:.0}</text>",
                px(f * tmax),
                y0 + ph + 15.0,
                f * tmax
            );
        }
        for (ci, c) in curves.iter().enumerate() {
            let col = colors[ci % colors.len()];
            let path: Vec<String> = c
                .points
                .iter()
                .filter(|p| p.1 > 0.0 && p.1.is_finite())
                .map(|p| format!("{:.1},{:.1}", px(p.0), py(p.1)))
                .collect();
            let _ = writeln!(
                s,
                "<polyline fill=\"none\" stroke=\"{col}\" stroke-width=\"1.8\" points=\"{}\"/>\n<text x=\"{}\" y=\"{}\" fill=\"{col}\">{}</text>",
                path.join(" "),
                x0 + pw - 120.0,
                y0 + 16.0 + 14.0 * ci as f64,
                c.label
            );
        }
    }
    s.push_str("</svg>\n");
    s
}
