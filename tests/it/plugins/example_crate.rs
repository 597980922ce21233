//! The example crate `custom_node` (`examples/custom_node.rs`): a Rust node added to a
//! working binary, next to plugins found on the command line, in `CGNODES_PLUGIN_PATH` and in
//! the user's config folder.

use cgnodes::plugin;
use std::path::{Path, PathBuf};
use std::process::Command;

use super::test_plugins;
use crate::common::root;

/// The example binary `custom_node`, which `cargo test` builds next to this test's folder
/// (`target/<profile>/examples/`). `None` (with a message) when only this test was built;
/// on CI that is an error.
pub(super) fn example_binary() -> Option<PathBuf> {
    let exe = std::env::current_exe().unwrap();
    let profile_dir = exe.parent()?.parent()?;
    let bin = profile_dir
        .join("examples")
        .join(format!("custom_node{}", std::env::consts::EXE_SUFFIX));
    if bin.exists() {
        return Some(bin);
    }
    let msg = format!(
        "{} is not built: run `cargo test` without target filters (it builds examples) or \
         `cargo build --example custom_node` first",
        bin.display()
    );
    crate::common::skip_or_fail("the example-binary checks", &msg);
    None
}

#[test]
fn the_example_crate_adds_a_node_to_a_working_binary() {
    let Some(bin) = example_binary() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let asset = root().join("assets/meshes/camel_b.obj");
    let graph = tmp.path().join("twist.json");
    std::fs::write(
        &graph,
        format!(
            r#"{{"format": "cgnodes-graph", "version": 1, "nodes": {{
            "load": {{"type": "mesh_load", "params": {{"path": {:?}}}}},
            "twist": {{"type": "twist", "params": {{"rate": 45}}, "inputs": {{"mesh": "load.mesh"}}}},
            "save": {{"type": "mesh_save", "params": {{"path": "twisted.obj"}}, "inputs": {{"mesh": "twist.mesh"}}}},
            "smooth": {{"type": "pl_echo", "params": {{"x": 21}}}},
            "show": {{"type": "print", "inputs": {{"value": "smooth.y"}}}}
        }}}}"#,
            asset.to_str().unwrap()
        ),
    )
    .unwrap();
    let out = tmp.path().join("out");
    let o = Command::new(&bin)
        .arg("run")
        .arg(&graph)
        .arg("--out")
        .arg(&out)
        .arg("--plugins")
        .arg(test_plugins())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    // The plugin node ran in the same binary (print writes to stdout).
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("42"),
        "{stderr}"
    );
    let before = cgnodes::nodes::mesh::mesh_load::load_mesh(&asset, &Default::default()).unwrap();
    let after =
        cgnodes::nodes::mesh::mesh_load::load_mesh(&out.join("twisted.obj"), &Default::default())
            .unwrap();
    assert_eq!(after.face_indices(), before.face_indices());
    let mut turned = 0.0f64;
    for (p, q) in before.positions.iter().zip(&after.positions) {
        // A twist about y keeps the height and the distance from the axis, and turns the
        // point by 45 degrees per unit of height.
        assert!((p[1] - q[1]).abs() < 1e-5);
        let (r0, r1) = (p[0].hypot(p[2]), q[0].hypot(q[2]));
        assert!((r0 - r1).abs() < 1e-5);
        if r0 > 1e-2 {
            let a0 = p[2].atan2(p[0]);
            let a1 = q[2].atan2(q[0]);
            let d = (a0 - a1 - 45f64.to_radians() * p[1]).rem_euclid(std::f64::consts::TAU);
            let d = d.min(std::f64::consts::TAU - d);
            assert!(d < 1e-3 / r0.min(1.0), "turn off by {d}");
            turned = turned.max((a0 - a1).abs());
        }
    }
    assert!(turned > 1e-3);
    // `nodes` lists the example's node and the plugin's nodes with where they come from.
    let o = Command::new(&bin)
        .args(["nodes", "--plugins"])
        .arg(test_plugins())
        .output()
        .unwrap();
    let listing = String::from_utf8_lossy(&o.stdout);
    let line = |name: &str| {
        listing
            .lines()
            .find(|l| l.starts_with(&format!("{name} ")))
            .unwrap_or_else(|| panic!("{name} missing from\n{listing}"))
            .to_string()
    };
    assert!(line("twist").contains("[example crate custom_node]"));
    assert!(line("pl_echo").contains("[plugin misbehave test ("));
    assert!(!line("math").contains('['));
    // Plugins also come from CGNODES_PLUGIN_PATH.
    let o = Command::new(&bin)
        .args(["describe", "pl_echo"])
        .env(plugin::PATH_VAR, test_plugins())
        .env("XDG_CONFIG_HOME", tmp.path())
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("from: plugin misbehave"));
    // And from the user's config folder.
    let user = tmp.path().join("cgnodes/plugins");
    std::fs::create_dir_all(&user).unwrap();
    copy_dir(&test_plugins().join("misbehave"), &user.join("misbehave"));
    let o = Command::new(&bin)
        .args(["describe", "pl_crash"])
        .env_remove(plugin::PATH_VAR)
        .env("XDG_CONFIG_HOME", tmp.path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.path().is_file() {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}
