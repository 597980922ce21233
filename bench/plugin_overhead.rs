//! Per-call overhead of an external-process plugin on a 100k-vertex mesh, broken down into
//! writing the `.npy` inputs, running the process (start, Python, numpy import, the work),
//! and reading the result back; compared with the same uniform Laplacian smoothing done
//! directly in Rust, and with bare process starts, all measured in this run.
//!
//! Run: `cargo bench --bench plugin_overhead` (needs python3 with numpy).

use cgnodes::plugin::{self, CallStats};
use cgnodes::types::{Mesh, Value};
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

const RUNS: usize = 5;

/// A triangulated `n` x `n` grid with a gentle bump.
fn grid(n: usize) -> Mesh {
    let mut p = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            p.push([x, y, 0.1 * (6.0 * x).sin() * (5.0 * y).cos()]);
        }
    }
    let mut t = Vec::with_capacity(2 * (n - 1) * (n - 1));
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = (j * n + i) as u32;
            let b = a + 1;
            let c = a + n as u32;
            t.push([a, b, c + 1]);
            t.push([a, c + 1, c]);
        }
    }
    Mesh::from_triangles(p, &t).expect("valid grid")
}

/// Uniform Laplacian smoothing in Rust (the baseline the plugin computes in numpy).
fn smooth_direct(mesh: &Mesh, iterations: usize, lambda: f64) -> Vec<[f64; 3]> {
    let topo = mesh.topology();
    let n = mesh.positions.len();
    let fixed: Vec<bool> = (0..n)
        .map(|v| topo.neighbors(v).is_empty() || topo.is_boundary_vertex(v))
        .collect();
    let mut p = mesh.positions.clone();
    for _ in 0..iterations {
        let prev = p.clone();
        for (v, pv) in p.iter_mut().enumerate() {
            let nb = topo.neighbors(v);
            if fixed[v] {
                continue;
            }
            let mut avg = [0.0; 3];
            for &j in nb {
                for c in 0..3 {
                    avg[c] += prev[j as usize][c];
                }
            }
            for c in 0..3 {
                pv[c] += lambda * (avg[c] / nb.len() as f64 - prev[v][c]);
            }
        }
    }
    p
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn time_ms(f: impl Fn()) -> f64 {
    median(
        (0..RUNS)
            .map(|_| {
                let t = Instant::now();
                f();
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect(),
    )
}

fn main() {
    let ok = Command::new("python3")
        .args(["-c", "import numpy"])
        .status()
        .is_ok_and(|s| s.success());
    if !ok {
        eprintln!("plugin_overhead: python3 with numpy is not installed; nothing measured");
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let p = plugin::load(&root.join("plugins/laplacian_smooth")).expect("example plugin");
    let decl = &p.nodes[0];
    let runner = p.runner();
    let mesh = grid(317);
    println!(
        "mesh: {} vertices, {} triangles; median of {RUNS} runs\n",
        mesh.num_vertices(),
        mesh.num_faces()
    );
    let _ = mesh.topology();
    let call = |iterations: i64| -> (CallStats, f64) {
        let mut inputs = BTreeMap::new();
        inputs.insert("mesh".to_string(), Value::from(mesh.clone()));
        inputs.insert("iterations".to_string(), Value::Int(iterations));
        inputs.insert("lambda".to_string(), Value::Float(0.5));
        inputs.insert("fix_boundary".to_string(), Value::Bool(true));
        let mut all: Vec<(f64, CallStats)> = (0..RUNS)
            .map(|_| {
                let t = Instant::now();
                let r = plugin::call(&runner, decl, &inputs, 0, None, 600.0).expect("plugin call");
                (t.elapsed().as_secs_f64() * 1e3, r.stats)
            })
            .collect();
        all.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (total, s) = all[RUNS / 2];
        (s, total)
    };
    let spawn_true = time_ms(|| {
        let _ = Command::new("true").status();
    });
    let py_bare = time_ms(|| {
        let _ = Command::new("python3").args(["-c", "pass"]).status();
    });
    let py_numpy = time_ms(|| {
        let _ = Command::new("python3")
            .args(["-c", "import numpy"])
            .status();
    });
    let (s0, total0) = call(0);
    let (s10, total10) = call(10);
    let direct10 = time_ms(|| {
        std::hint::black_box(smooth_direct(&mesh, 10, 0.5));
    });
    println!("{:<52} {:>10}", "phase", "ms");
    println!(
        "{:<52} {:>10.2}",
        "bare process start+exit (`true`)", spawn_true
    );
    println!("{:<52} {:>10.2}", "python3 -c pass", py_bare);
    println!("{:<52} {:>10.2}", "python3 -c 'import numpy'", py_numpy);
    println!("-- plugin call, 0 iterations (pure overhead) --");
    println!(
        "{:<52} {:>10.2}",
        "  write request + .npy inputs", s0.encode_ms
    );
    println!("{:<52} {:>10.2}", "  process start (spawn)", s0.spawn_ms);
    println!(
        "{:<52} {:>10.2}",
        "  process run (python, numpy, np.load, np.save)", s0.run_ms
    );
    println!(
        "{:<52} {:>10.2}",
        "  read response + .npy outputs", s0.decode_ms
    );
    println!("{:<52} {:>10.2}", "  total", total0);
    println!("-- plugin call, 10 iterations --");
    println!("{:<52} {:>10.2}", "  write", s10.encode_ms);
    println!("{:<52} {:>10.2}", "  process run", s10.run_ms);
    println!("{:<52} {:>10.2}", "  read", s10.decode_ms);
    println!("{:<52} {:>10.2}", "  total", total10);
    println!(
        "{:<52} {:>10.2}",
        "direct Rust smoothing, 10 iterations (baseline)", direct10
    );
    println!();
    println!(
        "overhead per call (0-iteration call): {:.1} ms = {:.2}x `python3 -c 'import numpy'`; \
         cgnodes' own share (write + read): {:.1} ms",
        total0,
        total0 / py_numpy,
        s0.encode_ms + s0.decode_ms
    );
    println!(
        "10-iteration plugin call vs direct Rust: {:.2}x ({:.1} ms vs {:.1} ms)",
        total10 / direct10,
        total10,
        direct10
    );
}
