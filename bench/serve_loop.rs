//! The live-editing loop of `cgnodes serve`: the time from a parameter change on the page
//! (the widget's `change` event) to the updated outputs shown on it (every image loaded,
//! every mesh in the viewer), measured in the page's own clock, in headless chromium. The
//! loop's own cost is that time less the run's wall time (load, validation and the nodes,
//! as the server timed it): the file write, the events, the page's fetches and redraw.
//!
//! `cargo bench --bench serve_loop -- [--rounds N] [--screenshot PNG]`; writes
//! `bench/results/serve_loop.json`. The screenshot (the README's) is of the Tutte page.

#[path = "../tests/it/support/browser.rs"]
mod browser;
#[path = "record.rs"]
mod record;

use browser::Browser;
use serde_json::{json, Value as Json};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

/// A graph, the widget changed, and the two values it alternates between.
struct Case {
    name: &'static str,
    graph: &'static str,
    node: &'static str,
    socket: &'static str,
    values: [i64; 2],
}

const CASES: &[Case] = &[
    Case {
        name: "tutte_cotangent_circle",
        graph: "graphs/tutte_cotangent_circle.json",
        node: "checker",
        socket: "checker_squares",
        values: [8, 16],
    },
    Case {
        name: "arap_camelhead",
        graph: "graphs/arap_camelhead.json",
        node: "arap",
        socket: "iterations",
        values: [20, 21],
    },
];

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

/// Runs one case: `rounds` changes; each round's loop time and node time, ms.
fn measure(case: &Case, rounds: usize, screenshot: Option<&Path>) -> Json {
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join(Path::new(case.graph).file_name().unwrap());
    browser::graph_copy(case.graph, &g);
    let served = browser::serve(&g, &dir.path().join("out"));
    let mut b = Browser::launch();
    b.open(&served.url).unwrap();
    let long = Duration::from_secs(120);
    b.wait_for("window.cgnodes && window.cgnodes.shown[1]", long)
        .unwrap();
    if let Some(png) = screenshot {
        // Meshes in their viewers, then the page as a user sees it.
        b.wait_for(
            "[...document.querySelectorAll('figure.viewer')].every(f => f.dataset.loaded)",
            long,
        )
        .unwrap();
        let data = b.screenshot_base64(false).unwrap();
        let mut py = Command::new("python3")
            .args([
                "-c",
                "import base64, sys; open(sys.argv[1], 'wb').write(base64.b64decode(sys.stdin.read()))",
            ])
            .arg(png)
            .stdin(Stdio::piped())
            .spawn()
            .unwrap();
        py.stdin.take().unwrap().write_all(data.as_bytes()).unwrap();
        assert!(py.wait().unwrap().success());
        eprintln!("wrote {}", png.display());
    }
    let mut loops = Vec::new();
    let mut nodes = Vec::new();
    let mut dones = Vec::new();
    for r in 0..rounds {
        let v = case.values[r % 2];
        let version = r + 2;
        b.set_widget(case.node, case.socket, "input", &v.to_string());
        let shown = format!("window.cgnodes.shown[{version}]");
        b.wait_for(&shown, long).unwrap();
        let ms = b
            .eval(&format!("{shown} - window.cgnodes.editAt"))
            .unwrap()
            .as_f64()
            .unwrap();
        let to_done = b
            .eval(&format!(
                "window.cgnodes.done[{version}] - window.cgnodes.editAt"
            ))
            .unwrap()
            .as_f64()
            .unwrap();
        let ran = b
            .eval("fetch('/api/state').then(r => r.json()).then(s => s.ms)")
            .unwrap()
            .as_f64()
            .unwrap();
        eprintln!(
            "{:<24} round {r:2}: {ms:7.1} ms to the page, {to_done:7.1} ms to the run's end, run {ran:7.1} ms",
            case.name
        );
        loops.push(ms);
        dones.push(to_done);
        nodes.push(ran);
    }
    drop(served);
    let over: Vec<f64> = loops.iter().zip(&nodes).map(|(l, n)| l - n).collect();
    let (ml, mn, mo) = (
        median(&mut loops.clone()),
        median(&mut nodes.clone()),
        median(&mut over.clone()),
    );
    eprintln!(
        "{:<24} median {ml:.1} ms to the page, of which the run {mn:.1} ms, the loop {mo:.1} ms",
        case.name
    );
    json!({ "case": case.name, "graph": case.graph, "widget": format!("{}.{}", case.node, case.socket),
            "values": case.values, "loop_ms": loops, "to_done_ms": dones, "run_ms": nodes,
            "median_to_done_ms": median(&mut dones.clone()), "overhead_ms": over,
            "median_loop_ms": ml, "median_run_ms": mn, "median_overhead_ms": mo,
            "meets_aim": mo < 200.0 })
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |k: &str| {
        args.iter()
            .position(|a| a == k)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let rounds: usize = arg("--rounds").and_then(|r| r.parse().ok()).unwrap_or(10);
    let shot = arg("--screenshot").map(PathBuf::from);
    if !browser::chromium_available() {
        eprintln!("serve_loop: chromium is not installed (apt-get install -y chromium)");
        std::process::exit(1);
    }
    let cases: Vec<Json> = CASES
        .iter()
        .enumerate()
        .map(|(i, c)| measure(c, rounds, if i == 0 { shot.as_deref() } else { None }))
        .collect();
    let path = record::write(
        "serve_loop",
        &format!("cargo bench --bench serve_loop -- --rounds {rounds}"),
        json!({ "rounds": rounds, "cases": cases }),
    );
    eprintln!("wrote {}", path.display());
}
