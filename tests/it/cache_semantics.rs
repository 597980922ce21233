//! Honest cache semantics (issue 23): a cache written by another build is not served, a
//! stateful node's results are served only for the same history, files named through links
//! and an OBJ's MTL and textures are stamped, and `--cache-size` evicts the least recently
//! used entries.

use cgnodes::exec::{Executor, NodeStatus, RunOptions, RunReport};
use cgnodes::node::FileEnv;
use cgnodes::registry::Registry;
use cgnodes::types::Value;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Arc, Mutex};

/// Runs `exe` (the cgnodes binary or a copy) with `args`; returns the exit code and stderr.
fn cli(exe: &Path, args: &[&str]) -> (i32, String) {
    // A freshly copied executable may be briefly busy (ETXTBSY) while another test thread
    // forks with the copy's descriptor open: retry.
    let mut tries = 0;
    let o = loop {
        match Command::new(exe).args(args).env("CI", "1").output() {
            Ok(o) => break o,
            Err(e) if e.raw_os_error() == Some(26) && tries < 50 => {
                tries += 1;
                std::thread::sleep(std::time::Duration::from_millis(20));
            }
            Err(e) => panic!("{}: {e}", exe.display()),
        }
    };
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn cgnodes() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_cgnodes"))
}

/// The (ran, cached) counts of the summary lines `cgnodes run` prints, one per frame.
fn ran_cached(stderr: &str) -> Vec<(usize, usize)> {
    stderr
        .lines()
        .filter_map(|l| {
            let l = &l[l.find("ran ")?..];
            let mut w = l.split([' ', ',']).filter(|w| !w.is_empty());
            let ran = w.nth(1)?.parse().ok()?;
            let cached = w.nth(1)?.parse().ok()?;
            Some((ran, cached))
        })
        .collect()
}

/// Writes `text` as `name` in `dir` and returns its path as a string.
fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_string_lossy().into_owned()
}

/// Every entry file of a disk cache.
fn entries(cache: &Path) -> Vec<PathBuf> {
    let mut v = Vec::new();
    for sub in std::fs::read_dir(cache).unwrap().flatten() {
        if sub.path().is_dir() {
            v.extend(
                std::fs::read_dir(sub.path())
                    .unwrap()
                    .flatten()
                    .map(|e| e.path()),
            );
        }
    }
    v.retain(|p| p.extension().is_some_and(|e| e == "bin"));
    v
}

const ARITH: &str = r#"{"format":"cgnodes-graph","version":1,"nodes":{
  "a":{"type":"math","params":{"a":A,"b":2,"op":"mul"}},
  "b":{"type":"math","inputs":{"a":"a.value"},"params":{"b":1}},
  "w":{"type":"table_write","inputs":{"value":"b.value"},"params":{"path":"b.csv"}}}}"#;

#[test]
fn a_cache_written_by_another_build_is_not_served() {
    let t = tempfile::tempdir().unwrap();
    let g = write(t.path(), "g.json", &ARITH.replace('A', "3"));
    let cache = t.path().join("cache");
    let out = t.path().join("out");
    // A copy of the binary stands for another build: its stamp can be changed freely.
    let exe = t.path().join("cgnodes");
    std::fs::copy(cgnodes(), &exe).unwrap();
    let args = ["run", &g, "--cache", cache.to_str().unwrap(), "--out"];
    let run = |exe: &Path| {
        let (code, err) = cli(exe, &[&args[..], &[out.to_str().unwrap()]].concat());
        assert_eq!(code, 0, "{err}");
        ran_cached(&err)
    };
    assert_eq!(run(&exe), [(3, 0)]);
    assert_eq!(run(&exe), [(0, 3)], "same build: everything cached");
    // An upgraded (here: rebuilt) executable: its stamp differs, so no key matches.
    let f = std::fs::File::options().append(true).open(&exe).unwrap();
    f.set_modified(std::time::SystemTime::UNIX_EPOCH + std::time::Duration::from_secs(1))
        .unwrap();
    drop(f);
    assert_eq!(run(&exe), [(3, 0)], "another build recomputes everything");
    assert_eq!(run(&exe), [(0, 3)]);
    // Entries whose header names another build are misses, even under the same key.
    for e in entries(&cache) {
        let mut bytes = std::fs::read(&e).unwrap();
        bytes[12] ^= 0xff; // first byte of the build identity
        std::fs::write(&e, bytes).unwrap();
    }
    assert_eq!(
        run(&exe),
        [(3, 0)],
        "entries of another build are not decoded"
    );
}

/// A registry with a stateful node (`accumulate`: its total grows by `x` each frame and
/// starts at 0 without state) and a node that adds 100 and counts its executions.
fn stateful_registry(count: Arc<Mutex<usize>>) -> Registry {
    let mut r = cgnodes::nodes::builtin_registry();
    r.add(
        "accumulate",
        |b| {
            b.stateful();
            b.add_input::<f64>("x").default(1.0);
            b.add_output::<f64>("total");
        },
        |ctx| {
            let x: f64 = ctx.input("x")?;
            let st = ctx.state::<f64>()?;
            *st += x;
            let t = *st;
            ctx.set_output("total", t);
            Ok(())
        },
    );
    r.add(
        "plus_100",
        |b| {
            b.add_input::<f64>("x");
            b.add_output::<f64>("value");
        },
        move |ctx| {
            *count.lock().unwrap() += 1;
            let v = ctx.input::<f64>("x")? + 100.0;
            ctx.set_output("value", v);
            Ok(())
        },
    );
    r
}

fn value(r: &RunReport, node: &str) -> f64 {
    match r.output(node, "value") {
        Some(Value::Float(x)) => *x,
        other => panic!("{node}: {other:?} {:?}", r.errors()),
    }
}

#[test]
fn a_later_frame_range_is_not_served_frames_of_another_history() {
    let count = Arc::new(Mutex::new(0));
    let r = stateful_registry(count.clone());
    let t = tempfile::tempdir().unwrap();
    let g = cgnodes::graph::parse(
        r#"{"format":"cgnodes-graph","version":1,"nodes":{
          "acc":{"type":"accumulate"},
          "p":{"type":"plus_100","inputs":{"x":"acc.total"}}},"outputs":["p"]}"#,
        &t.path().join("g.json"),
        t.path(),
    )
    .unwrap();
    let v = cgnodes::validate::validate(&g, &r).unwrap();
    let opts = RunOptions {
        files: FileEnv {
            graph_dir: t.path().to_path_buf(),
            out_dir: t.path().join("out"),
            ..Default::default()
        },
        ..Default::default()
    };
    let cache = t.path().join("cache");
    // Each process is a fresh executor on the same disk cache.
    let process = || Executor::new(Some(1), Some(&cache)).unwrap();
    let a = process();
    let first: Vec<f64> = (0..=5).map(|f| value(&a.run(&v, &opts, f), "p")).collect();
    assert_eq!(first, [101.0, 102.0, 103.0, 104.0, 105.0, 106.0]);
    assert_eq!(*count.lock().unwrap(), 6);
    // `--frames 3..4` in a new process: the simulation starts at frame 3 from its initial
    // state, so frame 3 is 101, not the 104 that the first run's history gave.
    let b = process();
    let r3 = b.run(&v, &opts, 3);
    assert_eq!(value(&r3, "p"), 101.0);
    assert!(matches!(r3.node("p").unwrap().status, NodeStatus::Ran));
    assert_eq!(value(&b.run(&v, &opts, 4), "p"), 102.0);
    // The same history again (frames 0..5 from the start) is served from the cache.
    let c = process();
    let n = *count.lock().unwrap();
    for f in 0..=5 {
        let rep = c.run(&v, &opts, f);
        assert_eq!(value(&rep, "p"), first[f as usize]);
        assert!(matches!(rep.node("p").unwrap().status, NodeStatus::Cached));
    }
    assert_eq!(
        *count.lock().unwrap(),
        n,
        "identical histories hit the cache"
    );
    // Restarting the simulation in the same process (`reset_states`) starts a new history.
    c.reset_states();
    assert_eq!(value(&c.run(&v, &opts, 2), "p"), 101.0);
}

#[test]
fn a_cloth_run_over_later_frames_writes_what_a_fresh_run_writes() {
    let t = tempfile::tempdir().unwrap();
    let g = write(
        t.path(),
        "cloth.json",
        r#"{"format":"cgnodes-graph","version":1,"nodes":{
          "grid":{"type":"mesh_grid","params":{"cells_u":4,"cells_v":4}},
          "sim":{"type":"mass_spring","inputs":{"mesh":"grid.mesh"},
                 "params":{"integrator":"implicit","h":0.01,"substeps":2,"fixed":"top_corners"}},
          "save":{"type":"mesh_save","inputs":{"mesh":"sim.mesh"},"params":{"path":"c_{frame}.obj"}}}}"#,
    );
    let cache = t.path().join("cache");
    let run = |frames: &str, out: &str, cached: bool| {
        let o = t.path().join(out);
        let mut args = vec!["run", &g, "--frames", frames, "--out", o.to_str().unwrap()];
        if cached {
            args.extend(["--cache", cache.to_str().unwrap()]);
        }
        let (code, err) = cli(&cgnodes(), &args);
        assert_eq!(code, 0, "{err}");
        o
    };
    let read = |d: &Path, f: i64| std::fs::read_to_string(d.join(format!("c_{f}.obj"))).unwrap();
    let long = run("0..3", "out", true);
    let long_2 = read(&long, 2);
    let later = run("2..3", "out", true);
    let fresh = run("2..3", "fresh", false);
    for f in 2..=3 {
        assert_eq!(read(&later, f), read(&fresh, f), "frame {f}");
    }
    // The long run's frame 2 had stepped twice: serving it would have been a lie.
    assert_ne!(long_2, read(&fresh, 2));
}

/// Runs `g` in a new executor on `cache`; returns the report.
fn run_once(g: &cgnodes::validate::ValidGraph, dir: &Path, cache: &Path) -> RunReport {
    let opts = RunOptions {
        files: FileEnv {
            graph_dir: dir.to_path_buf(),
            out_dir: dir.join("out"),
            ..Default::default()
        },
        ..Default::default()
    };
    let rep = Executor::new(Some(1), Some(cache))
        .unwrap()
        .run(g, &opts, 0);
    assert!(rep.ok(), "{:?}", rep.errors());
    rep
}

fn status(r: &RunReport, id: &str) -> &'static str {
    match r.node(id).unwrap().status {
        NodeStatus::Ran => "ran",
        NodeStatus::Cached => "cached",
        _ => "other",
    }
}

#[test]
fn a_file_named_through_a_link_is_stamped() {
    let t = tempfile::tempdir().unwrap();
    let tri = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let quad = "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
    write(t.path(), "m.off", tri);
    let g = cgnodes::graph::parse(
        r#"{"format":"cgnodes-graph","version":1,"nodes":{
          "p":{"type":"value_string","params":{"value":"m.off"}},
          "m":{"type":"mesh_load","inputs":{"path":"p.value"}}},"outputs":["m"]}"#,
        &t.path().join("g.json"),
        t.path(),
    )
    .unwrap();
    let v = cgnodes::validate::validate(&g, &cgnodes::nodes::builtin_registry()).unwrap();
    let cache = t.path().join("cache");
    let verts = |r: &RunReport| match r.output("m", "mesh") {
        Some(Value::Mesh(m)) => m.num_vertices(),
        other => panic!("{other:?}"),
    };
    let r1 = run_once(&v, t.path(), &cache);
    assert_eq!((status(&r1, "m"), verts(&r1)), ("ran", 3));
    let r2 = run_once(&v, t.path(), &cache);
    assert_eq!((status(&r2, "m"), verts(&r2)), ("cached", 3));
    // The file behind the linked path changes: the loader runs again.
    write(t.path(), "m.off", quad);
    let r3 = run_once(&v, t.path(), &cache);
    assert_eq!((status(&r3, "m"), verts(&r3)), ("ran", 4));
    assert_eq!(status(&run_once(&v, t.path(), &cache), "m"), "cached");
}

#[test]
fn an_objs_mtl_and_textures_are_stamped() {
    let t = tempfile::tempdir().unwrap();
    write(
        t.path(),
        "s.obj",
        "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n",
    );
    write(t.path(), "s.mtl", "newmtl red\nKd 1 0 0\nmap_Kd tex.png\n");
    write(t.path(), "tex.png", "not really a png");
    let g = cgnodes::graph::parse(
        r#"{"format":"cgnodes-graph","version":1,"nodes":{
          "s":{"type":"scene_load","params":{"path":"s.obj"}}},"outputs":["s"]}"#,
        &t.path().join("g.json"),
        t.path(),
    )
    .unwrap();
    let v = cgnodes::validate::validate(&g, &cgnodes::nodes::builtin_registry()).unwrap();
    let cache = t.path().join("cache");
    let kd = |r: &RunReport| match r.output("s", "scene") {
        Some(Value::Scene(s)) => s.objects[0].material.as_ref().unwrap().base_color,
        other => panic!("{other:?}"),
    };
    let r = run_once(&v, t.path(), &cache);
    assert_eq!((status(&r, "s"), kd(&r)), ("ran", [1.0, 0.0, 0.0]));
    assert_eq!(status(&run_once(&v, t.path(), &cache), "s"), "cached");
    // Same size, maybe the same second: the MTL's content is in the key.
    write(t.path(), "s.mtl", "newmtl red\nKd 0 1 0\nmap_Kd tex.png\n");
    let r = run_once(&v, t.path(), &cache);
    assert_eq!((status(&r, "s"), kd(&r)), ("ran", [0.0, 1.0, 0.0]));
    // A texture the MTL names changes: the node runs again.
    write(t.path(), "tex.png", "still not a png!");
    assert_eq!(status(&run_once(&v, t.path(), &cache), "s"), "ran");
    assert_eq!(status(&run_once(&v, t.path(), &cache), "s"), "cached");
}

/// Total length of a cache's entries.
fn cache_bytes(cache: &Path) -> u64 {
    entries(cache)
        .iter()
        .map(|e| std::fs::metadata(e).unwrap().len())
        .sum()
}

#[test]
fn cache_size_evicts_the_least_recently_used_entries() {
    let t = tempfile::tempdir().unwrap();
    let old = write(t.path(), "old.json", &ARITH.replace('A', "3"));
    let new = write(t.path(), "new.json", &ARITH.replace('A', "4"));
    let out = t.path().join("out");
    let run = |g: &str, cache: &Path, size: &str| {
        let (code, err) = cli(
            &cgnodes(),
            &[
                "run",
                g,
                "--cache",
                cache.to_str().unwrap(),
                "--cache-size",
                size,
                "--out",
                out.to_str().unwrap(),
            ],
        );
        assert_eq!(code, 0, "{err}");
        (ran_cached(&err), err)
    };
    // How much the new graph's entries take, measured in a cache of their own.
    let alone = t.path().join("alone");
    run(&new, &alone, "0");
    let new_bytes = cache_bytes(&alone);
    assert!(new_bytes > 0);
    let cache = t.path().join("cache");
    run(&old, &cache, "0");
    assert_eq!(cache_bytes(&cache), new_bytes, "same shapes, same sizes");
    // Room for one graph's entries: the older graph's go.
    let (rc, err) = run(&new, &cache, &new_bytes.to_string());
    assert_eq!(rc, [(3, 0)]);
    assert!(
        err.contains("removed 3 least recently used entries"),
        "{err}"
    );
    assert_eq!(cache_bytes(&cache), new_bytes);
    assert_eq!(
        run(&new, &cache, "0").0,
        [(0, 3)],
        "the recent entries stay"
    );
    assert_eq!(run(&old, &cache, "0").0, [(3, 0)], "the old entries went");
    // A hit counts as a use: serving `new` makes `old` the least recently used.
    assert_eq!(run(&new, &cache, "0").0, [(0, 3)]);
    run(&new, &cache, &new_bytes.to_string());
    assert_eq!(run(&new, &cache, "0").0, [(0, 3)]);
    assert_eq!(run(&old, &cache, "0").0, [(3, 0)]);
    // The default limit (1 GiB) keeps everything here; a bad size is a usage error.
    let (code, err) = cli(&cgnodes(), &["run", &new, "--cache-size", "lots"]);
    assert_eq!(code, 2, "{err}");
}
