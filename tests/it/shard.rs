//! Sharding for clusters (`--shard I/N`, docs/cluster.md), through the real binary: sweep
//! parts merged equal the unsharded sweep, the merge refuses incomplete or foreign parts,
//! frame blocks together write exactly the unsharded outputs, stateful graphs are refused,
//! and two processes sharing a cache folder race safely.

use crate::common::asset;
use std::path::Path;
use std::process::{Command, Output};

const GRAPH: &str = r#"{"format":"cgnodes-graph","version":1,"nodes":{
 "d":{"type":"math","params":{"op":"div","a":8,"b":2}},
 "e":{"type":"math","params":{"op":"sub","b":4},"inputs":{"a":"d.value"}}}}"#;

fn cgnodes(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cgnodes"))
        .current_dir(dir)
        .args(args)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("JOB_COMPLETION_INDEX")
        .output()
        .unwrap()
}

fn ok(o: &Output) -> &Output {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

/// A sweep CSV with the timing columns (total_ms, ms:NODE) blanked: what two runs share.
fn results(path: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let csv = cgnodes::io::csv::read(&text, false, false)
        .unwrap()
        .unwrap();
    let timing: Vec<bool> = csv
        .header
        .iter()
        .map(|h| h == "total_ms" || h.starts_with("ms:"))
        .collect();
    std::iter::once(&csv.header)
        .chain(&csv.rows)
        .map(|r| {
            r.iter()
                .zip(&timing)
                .map(|(f, &t)| if t { String::new() } else { f.clone() })
                .collect()
        })
        .collect()
}

const SWEEP: [&str; 9] = [
    "sweep",
    "g.json",
    "--vary",
    "d.b=0,1,2,4",
    "--vary",
    "d.op=div,mul",
    "--repeat",
    "2",
    "--measure=e.value",
];

#[test]
fn sharded_sweep_parts_merge_into_the_unsharded_sweep() {
    let d = tempfile::tempdir().unwrap();
    std::fs::write(d.path().join("g.json"), GRAPH).unwrap();
    let mut whole = SWEEP.to_vec();
    whole.extend(["--csv", "all.csv"]);
    ok(&cgnodes(d.path(), &whole));
    let want = results(&d.path().join("all.csv"));
    // 8 combinations x 2 repeats, one of them (b = 0, div) failing twice.
    assert_eq!(want.len(), 1 + 16);
    for n in [1usize, 3, 5, 9] {
        let mut parts = Vec::new();
        for i in 0..n {
            let (shard, csv) = (format!("{i}/{n}"), format!("part-{n}-{i}.csv"));
            let mut a = SWEEP.to_vec();
            a.extend(["--shard", &shard, "--csv", &csv]);
            ok(&cgnodes(d.path(), &a));
            parts.push(csv);
        }
        let mut m: Vec<&str> = vec!["sweep-merge"];
        // Parts in any order.
        m.extend(parts.iter().rev().map(String::as_str));
        m.extend(["--csv", "merged.csv", "--plot", "merged.svg", "--x", "d.b"]);
        ok(&cgnodes(d.path(), &m));
        assert_eq!(results(&d.path().join("merged.csv")), want, "{n} shards");
        let svg = std::fs::read_to_string(d.path().join("merged.svg")).unwrap();
        assert!(svg.contains("<svg"));
    }
    // `--shard auto` in a Slurm array task: shard 1 of 3 runs combinations 1, 4, 7.
    let mut a = SWEEP.to_vec();
    a.extend(["--shard", "auto", "--csv", "auto.csv"]);
    let o = Command::new(env!("CARGO_BIN_EXE_cgnodes"))
        .current_dir(d.path())
        .args(&a)
        .env("SLURM_ARRAY_TASK_ID", "1")
        .env("SLURM_ARRAY_TASK_COUNT", "3")
        .output()
        .unwrap();
    ok(&o);
    let combos: Vec<String> = results(&d.path().join("auto.csv"))[1..]
        .iter()
        .map(|r| format!("{} {}", r[0], r[1]))
        .collect();
    assert_eq!(
        combos,
        ["1/3 1", "1/3 1", "1/3 4", "1/3 4", "1/3 7", "1/3 7"]
    );
    // No environment: a clear error.
    let o = cgnodes(d.path(), &a);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("SLURM_ARRAY_TASK_ID"), "{}", stderr(&o));
}

#[test]
fn sweep_merge_names_missing_duplicated_and_mismatched_parts() {
    let d = tempfile::tempdir().unwrap();
    std::fs::write(d.path().join("g.json"), GRAPH).unwrap();
    for i in 0..3 {
        let (shard, csv) = (format!("{i}/3"), format!("p{i}.csv"));
        let mut a = SWEEP.to_vec();
        a.extend(["--shard", &shard, "--csv", &csv]);
        ok(&cgnodes(d.path(), &a));
    }
    let merge = |parts: &[&str]| {
        let mut a = vec!["sweep-merge"];
        a.extend(parts);
        a.extend(["--csv", "m.csv"]);
        let o = cgnodes(d.path(), &a);
        assert_eq!(o.status.code(), Some(3), "{parts:?} should fail");
        stderr(&o)
    };
    // Shard 2 of 3 runs combinations 2 and 5 (round robin).
    let e = merge(&["p0.csv", "p1.csv"]);
    assert!(
        e.contains("missing") && e.contains("shard 2/3 runs combinations 2, 5"),
        "{e}"
    );
    let e = merge(&["p0.csv", "p1.csv", "p2.csv", "p1.csv"]);
    assert!(
        e.contains("duplicated") && e.contains("combination 1 (d.b=0, d.op=mul)"),
        "{e}"
    );
    // A part missing one repeat of one combination.
    let text = std::fs::read_to_string(d.path().join("p2.csv")).unwrap();
    let cut: Vec<&str> = text
        .lines()
        .filter(|l| !l.starts_with("2/3,5,8,2,mul,1,"))
        .collect();
    assert_eq!(cut.len(), text.lines().count() - 1);
    std::fs::write(d.path().join("p2cut.csv"), cut.join("\n")).unwrap();
    let e = merge(&["p0.csv", "p1.csv", "p2cut.csv"]);
    assert!(e.contains("5 (repeat 1)"), "{e}");
    // A part of another sweep (another measure).
    let mut a = SWEEP.to_vec();
    a.extend([
        "--measure",
        "d.value",
        "--shard",
        "2/3",
        "--csv",
        "other.csv",
    ]);
    ok(&cgnodes(d.path(), &a));
    let e = merge(&["p0.csv", "p1.csv", "other.csv"]);
    assert!(
        e.contains("mismatched columns") && e.contains("d.value"),
        "{e}"
    );
    // An unsharded sweep's CSV is no part.
    let mut a = SWEEP.to_vec();
    a.extend(["--csv", "whole.csv"]);
    ok(&cgnodes(d.path(), &a));
    let e = merge(&["whole.csv"]);
    assert!(e.contains("not a part of a sharded sweep"), "{e}");
    assert!(!d.path().join("m.csv").exists());
    // The sweep file the parts ran gives the chart options and must match their columns.
    let spec = |measure: &str| {
        format!(
            r#"{{"graph": "g.json", "vary": [{{"param": "d.b", "values": [0, 1, 2, 4]}},
            {{"param": "d.op", "values": ["div", "mul"]}}], "repeat": 2,
            "measure": ["{measure}"], "x": "d.b", "log_y": true}}"#
        )
    };
    std::fs::write(d.path().join("s.json"), spec("e.value")).unwrap();
    let o = cgnodes(
        d.path(),
        &[
            "sweep-merge",
            "p0.csv",
            "p1.csv",
            "p2.csv",
            "--sweep",
            "s.json",
            "--plot",
            "s.svg",
        ],
    );
    ok(&o);
    assert!(d.path().join("s.svg").exists());
    std::fs::write(d.path().join("t.json"), spec("d.value")).unwrap();
    let o = cgnodes(
        d.path(),
        &[
            "sweep-merge",
            "p0.csv",
            "p1.csv",
            "p2.csv",
            "--sweep",
            "t.json",
        ],
    );
    assert_eq!(o.status.code(), Some(3));
    assert!(stderr(&o).contains("mismatched columns"), "{}", stderr(&o));
}

/// Every file below `dir` with its bytes, by relative path.
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().to_string(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

#[test]
fn frame_shards_write_exactly_the_unsharded_outputs() {
    let d = tempfile::tempdir().unwrap();
    let g = asset("graphs/frames_counter.json");
    let g = g.to_str().unwrap();
    ok(&cgnodes(
        d.path(),
        &[
            "run",
            g,
            "--frames",
            "0..9",
            "--out",
            "whole",
            "-q",
            "--no-report",
        ],
    ));
    let want = files(&d.path().join("whole"));
    // Ten JSON tables, each with its provenance sidecar (the same in every shard).
    assert_eq!(want.len(), 20);
    // 4 shards of 10 frames, sharing one --out; then 12 shards, some with no frames.
    for n in [4, 12] {
        let out = format!("shared{n}");
        for i in 0..n {
            let s = format!("{i}/{n}");
            let o = ok(&cgnodes(
                d.path(),
                &["run", g, "--frames", "0..9", "--out", &out, "--shard", &s],
            ))
            .clone();
            let wrote = stderr(&o).matches("wrote ").count();
            // Blocks of 2 or 3 frames (4 shards); 0 or 1 (12 shards).
            assert!(wrote <= 10usize.div_ceil(n), "{s}: {wrote}");
        }
        assert_eq!(files(&d.path().join(&out)), want, "{n} shards");
    }
}

#[test]
fn frame_sharding_refuses_a_stateful_graph_and_points_to_sweeps() {
    let d = tempfile::tempdir().unwrap();
    let g = asset("graphs/cloth_hang.json");
    let o = cgnodes(
        d.path(),
        &[
            "run",
            g.to_str().unwrap(),
            "--frames",
            "0..3",
            "--shard",
            "1/2",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("keeps state between frames") && e.contains("cgnodes sweep"),
        "{e}"
    );
    assert!(!d.path().join("out").exists(), "nothing ran");
}

#[test]
fn two_processes_writing_the_same_cache_entries_both_succeed() {
    let d = tempfile::tempdir().unwrap();
    let g = asset("graphs/arithmetic.json");
    let g = g.to_str().unwrap();
    for round in 0..6 {
        let cache = format!("cache{round}");
        let spawn = |out: &str| {
            Command::new(env!("CARGO_BIN_EXE_cgnodes"))
                .current_dir(d.path())
                .args(["run", g, "--cache", &cache, "--out", out])
                .output()
        };
        // Both processes start together and compute, then write, the same five keys (the
        // writer's key includes its output folder, which they share as shards do).
        let (a, b) = std::thread::scope(|s| {
            let a = s.spawn(|| spawn("o").unwrap());
            let b = s.spawn(|| spawn("o").unwrap());
            (a.join().unwrap(), b.join().unwrap())
        });
        ok(&a);
        ok(&b);
        let mut entries = Vec::new();
        for sub in std::fs::read_dir(d.path().join(&cache)).unwrap() {
            for f in std::fs::read_dir(sub.unwrap().path()).unwrap() {
                entries.push(f.unwrap().file_name().to_string_lossy().to_string());
            }
        }
        // One entry per node, no temporary file left.
        assert_eq!(entries.len(), 5, "{entries:?}");
        assert!(entries.iter().all(|e| e.ends_with(".bin")), "{entries:?}");
        // The entries are valid: a third run is served wholly from them.
        let c = ok(&spawn("o").unwrap()).clone();
        assert!(stderr(&c).contains("ran 0, cached 5"), "{}", stderr(&c));
        let csv = std::fs::read_to_string(d.path().join("o/circle_area.csv")).unwrap();
        assert!(csv.contains("12.566370614359"), "{csv}");
    }
}

#[test]
fn kubernetes_manifests_are_batch_v1_jobs_that_shard_and_merge() {
    let job = |name: &str| -> serde_json::Value {
        let p = asset(&format!("examples/k8s/{name}"));
        serde_json::from_str(&std::fs::read_to_string(&p).unwrap())
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()))
    };
    for (file, indexed) in [("sweep-job.json", true), ("merge-job.json", false)] {
        let j = job(file);
        assert_eq!(j["apiVersion"], "batch/v1", "{file}");
        assert_eq!(j["kind"], "Job", "{file}");
        assert!(j["metadata"]["name"]
            .as_str()
            .is_some_and(|n| !n.is_empty()));
        let spec = &j["spec"];
        let completions = spec["completions"].as_u64().unwrap();
        assert!(spec["parallelism"].as_u64().unwrap() <= completions);
        let pod = &spec["template"]["spec"];
        // The Job API accepts only Never or OnFailure for a Job's pods.
        assert!(["Never", "OnFailure"].contains(&pod["restartPolicy"].as_str().unwrap()));
        let containers = pod["containers"].as_array().unwrap();
        assert!(!containers.is_empty());
        let volumes: Vec<&str> = pod["volumes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v["name"].as_str().unwrap())
            .collect();
        for c in containers {
            assert!(c["name"].is_string() && c["image"].is_string(), "{file}");
            let words: Vec<&str> = c["command"]
                .as_array()
                .unwrap()
                .iter()
                .chain(c["args"].as_array().unwrap())
                .map(|a| a.as_str().unwrap())
                .collect();
            for m in c["volumeMounts"].as_array().unwrap() {
                assert!(volumes.contains(&m["name"].as_str().unwrap()), "{file}");
            }
            let line = words.join(" ");
            if indexed {
                assert_eq!(spec["completionMode"], "Indexed");
                // Each pod reads its index and the shard count the Job runs.
                let shards = format!("--shard auto --shards {completions}");
                assert!(line.contains(&shards), "{line}");
                assert!(line.contains("part-$(JOB_COMPLETION_INDEX).csv"), "{line}");
                assert_eq!(words[..2], ["cgnodes", "sweep"]);
            } else {
                assert!(line.contains("cgnodes sweep-merge"), "{line}");
            }
        }
    }
    // The sweep the ConfigMap carries parses as a sweep file.
    let s = std::fs::read_to_string(asset("examples/k8s/sweep.json")).unwrap();
    let spec: cgnodes::sweep::SweepSpec = serde_json::from_str(&s).unwrap();
    assert!(spec.graph.is_absolute());
}

#[test]
fn slurm_scripts_parse_and_chain_the_merge_after_the_array() {
    let dir = asset("examples/slurm");
    for f in std::fs::read_dir(&dir).unwrap() {
        let p = f.unwrap().path();
        let o = Command::new("bash").arg("-n").arg(&p).output().unwrap();
        assert!(o.status.success(), "{}: {}", p.display(), stderr(&o));
    }
    for (submit, task) in [
        ("submit_sweep.sh", "sweep.sbatch"),
        ("submit_frames.sh", "frames.sbatch"),
    ] {
        let s = std::fs::read_to_string(dir.join(submit)).unwrap();
        assert!(
            s.contains("--array=0-") && s.contains("--dependency=afterok:"),
            "{submit}"
        );
        let t = std::fs::read_to_string(dir.join(task)).unwrap();
        assert!(t.contains("--shard auto"), "{task}");
    }
}

/// The `ms:p` column of a sweep CSV (the wall time of node `p`, 0 when it was cached).
fn ms_p(path: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(path).unwrap();
    let csv = cgnodes::io::csv::read(&text, false, false)
        .unwrap()
        .unwrap();
    let col = csv.header.iter().position(|h| h == "ms:p").unwrap();
    csv.rows.iter().map(|r| r[col].parse().unwrap()).collect()
}

#[test]
fn sweep_shards_share_a_cache_folder() {
    // `p` does not depend on the varied parameter: with a shared --cache, the second shard
    // (another process) reads it from the folder the first one wrote, even in its first run.
    let d = tempfile::tempdir().unwrap();
    let graph = r#"{"format":"cgnodes-graph","version":1,"nodes":{
 "p":{"type":"mesh_plane","params":{"subdivisions":100}},
 "i":{"type":"mesh_info","inputs":{"mesh":"p.mesh"}},
 "d":{"type":"math","params":{"op":"mul","a":3,"b":1}}}}"#;
    std::fs::write(d.path().join("g.json"), graph).unwrap();
    let sweep = |shard: &str, csv: &str, cache: &str| {
        ok(&cgnodes(
            d.path(),
            &[
                "sweep",
                "g.json",
                "--vary",
                "d.b=1,2,3,4",
                "--measure=d.value",
                "--measure=i.table:vertices",
                "--shard",
                shard,
                "--csv",
                csv,
                "--cache",
                cache,
            ],
        ));
    };
    sweep("0/2", "p0.csv", "shared");
    sweep("1/2", "p1.csv", "shared");
    let (first, second) = (
        ms_p(&d.path().join("p0.csv")),
        ms_p(&d.path().join("p1.csv")),
    );
    assert!(first[0] > 0.0, "{first:?}");
    assert!(second.iter().all(|&t| t == 0.0), "{second:?}");
    // Control: the same shard with a folder of its own computes `p` in its first run.
    sweep("1/2", "p1_alone.csv", "own");
    assert!(ms_p(&d.path().join("p1_alone.csv"))[0] > 0.0);
    // and the shared-cache parts merge into the unsharded sweep
    ok(&cgnodes(
        d.path(),
        &["sweep-merge", "p0.csv", "p1.csv", "--csv", "merged.csv"],
    ));
    ok(&cgnodes(
        d.path(),
        &[
            "sweep",
            "g.json",
            "--vary",
            "d.b=1,2,3,4",
            "--measure=d.value",
            "--measure=i.table:vertices",
            "--csv",
            "all.csv",
        ],
    ));
    assert_eq!(
        results(&d.path().join("merged.csv")),
        results(&d.path().join("all.csv"))
    );
}
