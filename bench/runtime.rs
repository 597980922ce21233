//! Runtime overhead: a generated graph of 10,000 small nodes, parsed, validated and run,
//! then run again with everything cached. `cargo bench --bench runtime`.

use cgnodes::exec::{Executor, RunOptions};
use cgnodes::node::FileEnv;
use cgnodes::nodes::builtin_registry;
use std::path::Path;
use std::time::Instant;

/// A graph of `n` nodes: `n/10` independent chains of `math` nodes, each summed into a table.
fn generate(n: usize) -> String {
    let chains = n / 10;
    let mut nodes = Vec::new();
    for c in 0..chains {
        nodes.push(format!(
            r#""c{c}_0": {{"type": "value_float", "params": {{"value": {c}}}}}"#
        ));
        for k in 1..9 {
            nodes.push(format!(
                r#""c{c}_{k}": {{"type": "math", "params": {{"op": "add", "b": 1}}, "inputs": {{"a": "c{c}_{}.value"}}}}"#,
                k - 1
            ));
        }
        nodes.push(format!(r#""c{c}_9": {{"type": "print", "params": {{"label": "x"}}, "inputs": {{"value": "c{c}_8.value"}}}}"#));
    }
    format!(
        r#"{{"format": "cgnodes-graph", "version": 1, "nodes": {{{}}}, "outputs": []}}"#,
        nodes.join(",\n")
    )
}

fn main() {
    let n = 10_000;
    let text = generate(n);
    // Evaluate the math chains but not the printers (so the figure is not stdout speed).
    let text = text.replace(r#""outputs": []"#, &{
        let ids: Vec<String> = (0..n / 10).map(|c| format!("\"c{c}_8\"")).collect();
        format!(r#""outputs": [{}]"#, ids.join(","))
    });
    let registry = builtin_registry();
    let exec = Executor::new(None, None).unwrap();
    let opts = RunOptions {
        files: FileEnv {
            out_dir: std::env::temp_dir(),
            ..Default::default()
        },
        ..Default::default()
    };
    let mut rows = Vec::new();
    for rep in 0..5 {
        let t0 = Instant::now();
        let g = cgnodes::graph::parse(&text, Path::new("generated.json"), Path::new(".")).unwrap();
        let t1 = Instant::now();
        let v = cgnodes::validate::validate(&g, &registry).unwrap();
        let t2 = Instant::now();
        exec.reset_states();
        let fresh = Executor::new(None, None).unwrap();
        let r = fresh.run(&v, &opts, 0);
        let t3 = Instant::now();
        assert!(r.ok() && r.executed().len() == n / 10 * 9);
        let r2 = fresh.run(&v, &opts, 0);
        let t4 = Instant::now();
        assert!(r2.executed().is_empty());
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        rows.push([ms(t0, t1), ms(t1, t2), ms(t2, t3), ms(t3, t4)]);
        if rep == 0 {
            println!(
                "graph: {n} nodes, {} run per evaluation",
                r.executed().len()
            );
        }
    }
    rows.sort_by(|a, b| (a[0] + a[1] + a[2]).total_cmp(&(b[0] + b[1] + b[2])));
    let m = rows[rows.len() / 2];
    println!("| step | ms (median of 5) |\n|---|---|");
    println!("| parse | {:.1} |\n| validate | {:.1} |\n| run (cold) | {:.1} |\n| run (all cached) | {:.1} |", m[0], m[1], m[2], m[3]);
    println!("| validate + run (cold) | {:.1} |", m[1] + m[2]);
}
