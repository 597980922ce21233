//! Every example graph in `graphs/` validates and runs end to end on the shipped assets.

use cgnodes::exec::{Executor, NodeStatus, RunOptions};
use cgnodes::node::FileEnv;
use cgnodes::nodes::builtin_registry;
use std::path::Path;

#[test]
fn every_example_graph_runs() {
    let registry = builtin_registry();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("graphs");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    assert!(
        files.len() >= 3,
        "expected example graphs in {}",
        dir.display()
    );
    let mut failures = Vec::new();
    for f in &files {
        let g = match cgnodes::graph::load(f) {
            Ok(g) => g,
            Err(e) => {
                failures.push(format!("{e}"));
                continue;
            }
        };
        let (f0, f1) = g.spec.frames_hint().unwrap_or((0, 0));
        let valid = match cgnodes::validate::validate(&g, &registry) {
            Ok(v) => v,
            Err(errs) => {
                failures.extend(errs.iter().map(|e| e.to_string()));
                continue;
            }
        };
        // the Poisson graphs paste beside tests/it/poisson.rs's checks of the node's caches
        let _lock = std::fs::read_to_string(f)
            .is_ok_and(|t| t.contains("\"poisson_blend\""))
            .then(crate::common::poisson_lock);
        let out = tempfile::tempdir().unwrap();
        let exec = Executor::new(None, None).unwrap();
        let opts = RunOptions {
            files: FileEnv {
                graph_dir: valid.dir.clone(),
                out_dir: out.path().to_path_buf(),
                ..Default::default()
            },
            ..Default::default()
        };
        // Every writer (a node with a file-output socket) that ran writes a file in some frame.
        let writers: Vec<&str> = valid
            .nodes
            .iter()
            .filter(|n| {
                n.decl
                    .inputs
                    .iter()
                    .any(|s| s.file == cgnodes::node::FileRole::Output)
            })
            .map(|n| n.id.as_str())
            .collect();
        let mut ran = std::collections::BTreeSet::new();
        let mut wrote = std::collections::BTreeSet::new();
        for frame in f0..=f1 {
            let r = exec.run(&valid, &opts, frame);
            failures.extend(r.errors());
            assert!(!r.nodes.is_empty());
            for n in r.nodes.iter().filter(|n| writers.contains(&n.id.as_str())) {
                if matches!(n.status, NodeStatus::Ran) {
                    ran.insert(n.id.clone());
                }
                for p in &n.written {
                    assert!(
                        p.starts_with(out.path()),
                        "{}: {}",
                        f.display(),
                        p.display()
                    );
                    assert!(
                        p.is_file(),
                        "{}: {} is not a file",
                        f.display(),
                        p.display()
                    );
                    wrote.insert(n.id.clone());
                }
            }
        }
        for id in ran.difference(&wrote) {
            failures.push(format!(
                "{}: writer '{id}' ran but wrote no file",
                f.display()
            ));
        }
        if !writers.is_empty() && walk(out.path()) == 0 {
            failures.push(format!("{}: wrote no file", f.display()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn walk(p: &Path) -> usize {
    std::fs::read_dir(p)
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .map(|e| {
                    if e.path().is_dir() {
                        walk(&e.path())
                    } else {
                        1
                    }
                })
                .sum()
        })
        .unwrap_or(0)
}
