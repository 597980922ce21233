//! Semantics of `cgnodes run`, `validate` and `dot` that a hostile or careless user meets
//! (issue 23): frames after a failed simulation, unused branches with problems, the options
//! the graph commands share, and Ctrl-C during a plugin call.

#[cfg(unix)]
use crate::common::pid_alive;
use std::path::Path;
use std::process::{Command, Output};

/// Runs the `cgnodes` binary with `args` in `cwd`.
fn cgnodes(cwd: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cgnodes"))
        .current_dir(cwd)
        .env("CI", "1")
        .args(args)
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A one-triangle OBJ.
const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

#[test]
fn validate_and_dot_take_assets_like_run() {
    let d = tempfile::tempdir().unwrap();
    let assets = d.path().join("assets");
    std::fs::create_dir(&assets).unwrap();
    std::fs::write(assets.join("tri.obj"), TRIANGLE).unwrap();
    let graph = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
        "m": {"type": "mesh_load", "params": {"path": "tri.obj"}},
        "s": {"type": "mesh_save", "inputs": {"mesh": "m.mesh"}, "params": {"path": "t.obj"}}
    }}"#;
    std::fs::write(d.path().join("g.json"), graph).unwrap();
    // Without the asset folder the file is missing: exit code 3, naming the node.
    let o = cgnodes(d.path(), &["validate", "g.json"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("node 'm'"), "{}", stderr(&o));
    let o = cgnodes(d.path(), &["dot", "g.json"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    // With it, all three commands accept the graph.
    let o = cgnodes(d.path(), &["validate", "g.json", "--assets", "assets"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("ok (2 nodes)"));
    let o = cgnodes(d.path(), &["dot", "--assets", "assets", "g.json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("\"m\" -> \"s\""));
    let o = cgnodes(
        d.path(),
        &["run", "g.json", "--assets", "assets", "--out", "out", "-q"],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(d.path().join("out/t.obj").exists());
    // `--set` and `--f3d-aliases` are shared too: a bad aliases file is a usage error.
    let o = cgnodes(
        d.path(),
        &["validate", "g.json", "--set", "m.path=\"assets/tri.obj\""],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = cgnodes(d.path(), &["dot", "g.json", "--f3d-aliases", "nope.json"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

/// Sorted names of the files in `dir` (empty when it does not exist).
fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn a_failed_simulation_stays_failed_for_the_rest_of_the_frames() {
    // The course cloth with the semi-implicit integrator at h = 0.05 blows up at frame 2.
    // Before issue 23 frame 3 restarted from the rest state and the run wrote frames
    // 0, 1, 3, 4 of two different histories and exited 0.
    let d = tempfile::tempdir().unwrap();
    let graph = crate::common::asset("graphs/cloth_hang.json");
    let o = cgnodes(
        d.path(),
        &[
            "run",
            graph.to_str().unwrap(),
            "--set",
            "semi.h=0.05",
            "--set",
            "semi.substeps=1",
            "--target",
            "save_semi",
            "--target",
            "save_impl",
            "--frames",
            "0..5",
            "--out",
            "out",
        ],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(
        files_in(&d.path().join("out/semi_implicit")),
        ["cloth_0000.obj", "cloth_0001.obj"],
        "{err}"
    );
    // The independent implicit cloth ran every frame.
    assert_eq!(
        files_in(&d.path().join("out/implicit")),
        (0..=5)
            .map(|f| format!("cloth_{f:04}.usda"))
            .collect::<Vec<_>>(),
        "{err}"
    );
    // The failure, the blocked writer and the stop are each reported once.
    assert_eq!(err.matches("failed [unstable]").count(), 1, "{err}");
    assert_eq!(
        err.matches("node 'save_semi' (mesh_save) did not run")
            .count(),
        1,
        "{err}"
    );
    assert_eq!(
        err.matches("node 'semi' (mass_spring) keeps state between frames: it and the nodes it feeds stay failed for frames 3..5").count(),
        1,
        "{err}"
    );
    assert!(
        err.contains("[frame 5] ran 2, cached 1, failed 0, blocked 1, stopped 1"),
        "{err}"
    );
}

#[test]
fn a_stopped_simulation_restarts_only_after_reset_states() {
    use cgnodes::exec::{Executor, NodeStatus, RunOptions};
    let text = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
        "grid": {"type": "mesh_grid", "params": {"cells_u": 6, "cells_v": 6}},
        "sim": {"type": "mass_spring", "inputs": {"mesh": "grid.mesh"},
                "params": {"integrator": "semi_implicit", "h": 0.05, "substeps": 1, "fixed": "top_corners"}},
        "n": {"type": "mesh_info", "inputs": {"mesh": "sim.mesh"}}
    }, "outputs": ["n"]}"#;
    let d = tempfile::tempdir().unwrap();
    let g = cgnodes::graph::parse(text, &d.path().join("g.json"), d.path()).unwrap();
    let reg = cgnodes::nodes::builtin_registry();
    let valid = cgnodes::validate::validate(&g, &reg).unwrap();
    let exec = Executor::new(Some(1), None).unwrap();
    let opts = RunOptions::default();
    let reports: Vec<_> = (0..8).map(|f| exec.run(&valid, &opts, f)).collect();
    let first = reports
        .iter()
        .position(|r| !r.ok())
        .expect("the cloth should blow up");
    assert!(matches!(
        reports[first].node("sim").unwrap().status,
        NodeStatus::Failed(_)
    ));
    assert_eq!(exec.stopped_since("sim"), Some(first as i64));
    for r in &reports[first + 1..] {
        assert!(!r.ok());
        assert!(
            matches!(r.node("sim").unwrap().status, NodeStatus::Stopped { since } if since == first as i64)
        );
        assert!(matches!(&r.node("n").unwrap().status, NodeStatus::Blocked { by } if by == "sim"));
        // Reported in the frame where it failed, not again.
        assert!(r.errors().is_empty(), "{:?}", r.errors());
    }
    exec.reset_states();
    assert_eq!(exec.stopped_since("sim"), None);
    assert!(exec.run(&valid, &opts, 0).ok());
}

/// A graph with two branches: `w` writes a value, `s` saves a mesh from a missing file.
const BRANCHES: &str = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
    "x": {"type": "value_float", "params": {"value": 2.5}},
    "w": {"type": "table_write", "inputs": {"value": "x.value"}, "params": {"path": "x.json"}},
    "m": {"type": "mesh_load", "params": {"path": "missing.obj"}},
    "s": {"type": "mesh_save", "inputs": {"mesh": "m.mesh"}, "params": {"path": "m.obj"}}
}OUTPUTS}"#;

#[test]
fn a_missing_file_in_an_unused_branch_is_a_warning() {
    let d = tempfile::tempdir().unwrap();
    std::fs::write(d.path().join("g.json"), BRANCHES.replace("OUTPUTS", "")).unwrap();
    let o = cgnodes(
        d.path(),
        &["run", "g.json", "--target", "w", "--out", "out"],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(d.path().join("out/x.json").exists(), "{err}");
    assert!(!d.path().join("out/m.obj").exists(), "{err}");
    assert!(
        err.contains("warning: ") && err.contains("node 'm' (mesh_load): input 'path': file"),
        "{err}"
    );
    assert!(!err.contains("error"), "{err}");
    // The graph's own outputs choose the branch the same way for run. `validate` checks
    // every node (issue 56): the unused branch's missing file is an error there, and a
    // warning only when `--target` names the branch that is used.
    std::fs::write(
        d.path().join("o.json"),
        BRANCHES.replace("OUTPUTS", r#", "outputs": ["w"]"#),
    )
    .unwrap();
    let o = cgnodes(d.path(), &["run", "o.json", "--out", "out2"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("warning: "), "{}", stderr(&o));
    let o = cgnodes(d.path(), &["validate", "o.json"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("node 'm' (mesh_load): input 'path': file"),
        "{}",
        stderr(&o)
    );
    let o = cgnodes(d.path(), &["validate", "o.json", "--target", "w"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("warning: "), "{}", stderr(&o));
}

/// Two nodes that read each other and nothing that writes (issue 56).
const CYCLE: &str = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
    "a": {"type": "math", "inputs": {"a": "b.value"}},
    "b": {"type": "math", "inputs": {"a": "a.value"}}
}}"#;

#[test]
fn validate_reports_a_cycle_that_no_output_needs() {
    let d = tempfile::tempdir().unwrap();
    std::fs::write(d.path().join("g.json"), CYCLE).unwrap();
    let o = cgnodes(d.path(), &["validate", "g.json"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("cycle"), "{}", stderr(&o));
    let o = cgnodes(d.path(), &["run", "g.json", "--out", "out"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
}

#[test]
fn run_with_nothing_that_writes_says_so() {
    let d = tempfile::tempdir().unwrap();
    let g = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
        "x": {"type": "value_float", "params": {"value": 2.5}}
    }}"#;
    std::fs::write(d.path().join("g.json"), g).unwrap();
    let o = cgnodes(d.path(), &["run", "g.json", "--out", "out"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("nothing to run: no node writes a file; name a --target"),
        "{}",
        stderr(&o)
    );
    let o = cgnodes(
        d.path(),
        &["run", "g.json", "--out", "out", "--target", "x"],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

#[test]
fn a_missing_file_in_the_used_branch_is_an_error() {
    let d = tempfile::tempdir().unwrap();
    std::fs::write(d.path().join("g.json"), BRANCHES.replace("OUTPUTS", "")).unwrap();
    for args in [
        &["run", "g.json", "--target", "s", "--out", "out"][..],
        &["run", "g.json", "--out", "out"][..],
        &["validate", "g.json"][..],
    ] {
        let o = cgnodes(d.path(), args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(3), "{args:?}: {err}");
        assert!(
            err.contains("error: ") && err.contains("node 'm' (mesh_load): input 'path': file"),
            "{err}"
        );
        assert!(err.contains("nothing was run"), "{err}");
        assert!(!d.path().join("out").exists());
    }
}

/// The parent of process `pid`, from /proc.
#[cfg(unix)]
fn parent_of(pid: i32) -> Option<i32> {
    let s = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    s.rsplit_once(')')?
        .1
        .split_whitespace()
        .nth(1)?
        .parse()
        .ok()
}

#[cfg(unix)]
#[test]
fn ctrl_c_kills_the_plugins_and_removes_the_temporaries() {
    let python = Command::new("python3")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !python {
        assert!(std::env::var_os("CI").is_none(), "CI=1 needs python3");
        eprintln!("python3 not found; Ctrl-C test skipped");
        return;
    }
    interrupt_a_plugin_run(libc::SIGINT);
    interrupt_a_plugin_run(libc::SIGTERM);
}

/// Runs a graph whose plugin hangs, sends `signal` once the plugin started its child, and
/// checks the exit code, the processes and the temporaries.
#[cfg(unix)]
fn interrupt_a_plugin_run(signal: libc::c_int) {
    let d = tempfile::tempdir().unwrap();
    let tmp = d.path().join("tmp");
    std::fs::create_dir(&tmp).unwrap();
    let pidfile = d.path().join("child.pid");
    // The misbehaving test plugin's `pl_hang` starts `sleep 3600` and sleeps for an hour.
    let graph = format!(
        r#"{{"format": "cgnodes-graph", "version": 1, "nodes": {{
        "hang": {{"type": "pl_hang", "params": {{"timeout": 3600.0, "pidfile": {:?}}}}},
        "show": {{"type": "print", "inputs": {{"value": "hang.y"}}}},
        "x": {{"type": "value_float", "params": {{"value": 1}}}},
        "w": {{"type": "table_write", "inputs": {{"value": "x.value"}}, "params": {{"path": "x.json"}}}}
    }}}}"#,
        pidfile.to_str().unwrap()
    );
    std::fs::write(d.path().join("g.json"), graph).unwrap();
    let plugins = crate::common::asset("tests/data/plugins/misbehave");
    let mut run = Command::new(env!("CARGO_BIN_EXE_cgnodes"))
        .current_dir(d.path())
        .env("TMPDIR", &tmp)
        .args(["--plugins", plugins.to_str().unwrap(), "run", "g.json"])
        .args(["--out", "out", "--threads", "2"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait (generously, for a loaded machine) until the plugin started its child.
    let mut child = None;
    for _ in 0..1200 {
        if let Some(p) = std::fs::read_to_string(&pidfile)
            .ok()
            .and_then(|s| s.trim().parse::<i32>().ok())
        {
            child = Some(p);
            break;
        }
        assert!(run.try_wait().unwrap().is_none(), "cgnodes ended early");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let child = child.expect("the plugin did not start its child within 60 s");
    let plugin = parent_of(child).expect("the plugin process");
    assert!(pid_alive(plugin as u32) && pid_alive(child as u32));
    // The plugin's call folder is a temporary in TMPDIR.
    assert!(
        std::fs::read_dir(&tmp).unwrap().count() > 0,
        "no call folder in TMPDIR"
    );
    let pid = i32::try_from(run.id()).unwrap();
    // SAFETY: kill(2) sends a signal to the process this test started.
    assert_eq!(unsafe { libc::kill(pid, signal) }, 0);
    let mut status = None;
    for _ in 0..600 {
        status = run.try_wait().unwrap();
        if status.is_some() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let Some(status) = status else {
        let _ = run.kill();
        panic!("cgnodes did not end within 30 s of signal {signal}");
    };
    let mut err = String::new();
    std::io::Read::read_to_string(&mut run.stderr.take().unwrap(), &mut err).unwrap();
    assert_eq!(status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    // Killed with SIGKILL by the time cgnodes exits; give the kernel a moment to reap them.
    for _ in 0..100 {
        if !pid_alive(plugin as u32) && !pid_alive(child as u32) {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    assert!(
        !pid_alive(plugin as u32),
        "the plugin {plugin} outlived signal {signal}"
    );
    assert!(
        !pid_alive(child as u32),
        "the plugin's child {child} outlived Ctrl-C"
    );
    // No temporaries: the call folder is gone, and nothing half-written in the output folder.
    let left: Vec<_> = std::fs::read_dir(&tmp).unwrap().collect();
    assert!(left.is_empty(), "{left:?}");
    let stray = files_in(&d.path().join("out"))
        .into_iter()
        .filter(|f| f.starts_with(".cgnodes-"))
        .count();
    assert_eq!(stray, 0);
}
