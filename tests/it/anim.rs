//! Skeletons and skinning: our LBS against usd-core's UsdSkel on the course's arm and a
//! four-joint, four-influence cylinder (at every time sample and between them), DQS against
//! LBS on a half-twisted cylinder (the candy-wrapper), and the errors bad UsdSkel input gets.

use crate::common::{asset, skip_or_fail};
use cgnodes::nodes::anim::skin::{skin_mesh, SkinMethod};
use cgnodes::nodes::mesh::mesh_info::signed_volume;
use cgnodes::nodes::mesh::mesh_load::{load_mesh, LoadOptions};
use cgnodes::nodes::mesh::usda::{parse_usda, read_skeleton, read_usda};
use cgnodes::types::Mesh;
use std::process::Command;

fn load(rel: &str, prim: &str) -> Mesh {
    let opts = LoadOptions {
        prim: prim.into(),
        apply_transform: true,
        ..Default::default()
    };
    load_mesh(&asset(rel), &opts).unwrap()
}

/// usd-core's skinned points at `times`, or `None` (skipped) when python3 lacks `pxr`.
fn usd_reference(test: &str, rel: &str, prim: &str, times: &[f64]) -> Option<Vec<Vec<[f64; 3]>>> {
    let script = asset("tests/data/usd_skin_reference.py");
    let mut cmd = Command::new("python3");
    cmd.arg(&script).arg(asset(rel)).arg(prim);
    cmd.args(times.iter().map(|t| t.to_string()));
    let out = match cmd.output() {
        Ok(o) => o,
        Err(e) => {
            skip_or_fail(test, &format!("python3 cannot run: {e}"));
            return None;
        }
    };
    if out.status.code() == Some(3) {
        skip_or_fail(test, "python3 has no pxr (pip install usd-core)");
        return None;
    }
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    Some(serde_json::from_slice(&out.stdout).unwrap())
}

fn diagonal(points: &[[f64; 3]]) -> f64 {
    let mut lo = [f64::MAX; 3];
    let mut hi = [f64::MIN; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
}

/// Our LBS equals `UsdSkel.SkinningQuery.ComputeSkinnedPoints` to 1e-6 of the skinned
/// mesh's bounding-box diagonal at `times` (samples, between samples, and outside them).
fn compare_with_usd(test: &str, rel: &str, prim: &str, times: &[f64]) {
    let Some(reference) = usd_reference(test, rel, prim, times) else {
        return;
    };
    let mesh = load(rel, prim);
    for (t, want) in times.iter().zip(&reference) {
        let got = skin_mesh(&mesh, None, *t, SkinMethod::Lbs)
            .unwrap()
            .mesh
            .positions;
        assert_eq!(got.len(), want.len());
        let tol = 1e-6 * diagonal(want);
        let worst = got
            .iter()
            .zip(want)
            .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max);
        assert!(
            worst <= tol,
            "{rel} at time {t}: off by {worst:e} > {tol:e}"
        );
        // The pose really moves between samples (the comparison is not of rest poses).
        if *t > 1.5 {
            let moved = got
                .iter()
                .zip(&mesh.positions)
                .any(|(a, b)| (a[1] - b[1]).abs() > 0.01);
            assert!(moved, "{rel} at time {t} did not move");
        }
    }
}

#[test]
fn lbs_equals_usd_core_on_the_course_arm() {
    compare_with_usd(
        "lbs_equals_usd_core_on_the_course_arm",
        "assets/course/arm.usda",
        "/Model/Mesh",
        &[-3.0, 1.0, 2.0, 4.75, 5.5, 9.9, 10.0, 14.0],
    );
}

#[test]
fn lbs_equals_usd_core_on_a_four_joint_cylinder() {
    compare_with_usd(
        "lbs_equals_usd_core_on_a_four_joint_cylinder",
        "tests/data/skin_cylinder.usda",
        "/Model/Tube",
        &[0.0, 1.0, 1.7, 2.5, 4.0, 5.25, 7.3, 9.99, 10.0, 12.0],
    );
}

#[test]
fn the_cylinder_has_four_influences_per_vertex_and_four_joints() {
    let m = load("tests/data/skin_cylinder.usda", "/Model/Tube");
    let b = m.skin.as_deref().unwrap();
    assert_eq!((b.influences, b.skeleton.joints.len()), (4, 4));
    assert_eq!(b.joint_indices.len(), 4 * m.num_vertices());
    assert!(b.skeleton.animation.as_ref().unwrap().rotations.times.len() == 3);
}

#[test]
fn held_at_the_ends_outside_the_samples() {
    let m = load("assets/course/arm.usda", "/Model/Mesh");
    let at = |t| {
        skin_mesh(&m, None, t, SkinMethod::Lbs)
            .unwrap()
            .mesh
            .positions
    };
    assert_eq!(at(-100.0), at(1.0));
    assert_eq!(at(1e6), at(10.0));
    assert_ne!(at(5.0), at(10.0));
}

#[test]
fn dqs_keeps_the_volume_of_a_half_twist_where_lbs_collapses() {
    let m = load("tests/data/twist_cylinder.usda", "/Model/Tube");
    let rest = signed_volume(&m);
    // The analytic volume of the 24-gon prism: (n/2) r^2 sin(2 pi / n) * length.
    let n = 24.0;
    let prism = n / 2.0 * 0.25 * (2.0 * std::f64::consts::PI / n).sin() * 4.0;
    assert!((rest - prism).abs() < 1e-6 * prism, "{rest} vs {prism}");
    let vol = |method, t| signed_volume(&skin_mesh(&m, None, t, method).unwrap().mesh);
    let (lbs, dqs) = (vol(SkinMethod::Lbs, 180.0), vol(SkinMethod::Dqs, 180.0));
    assert!(
        dqs >= 0.9 * rest,
        "DQS keeps {:.3} of the volume",
        dqs / rest
    );
    // LBS: a ring at weight w shrinks by |1 - 2w| at a half turn, so about 1/3 remains.
    assert!(
        lbs <= 0.4 * rest,
        "LBS keeps {:.3} of the volume",
        lbs / rest
    );
    // Both agree where nothing turns.
    assert!((vol(SkinMethod::Lbs, 0.0) - rest).abs() < 1e-9 * rest);
    assert!((vol(SkinMethod::Dqs, 0.0) - rest).abs() < 1e-9 * rest);
}

const SKEL_HEAD: &str = "#usda 1.0\ndef SkelRoot \"R\"\n{\n    def Skeleton \"S\"\n    {\n";

fn skeleton_error(body: &str) -> String {
    let text = format!("{SKEL_HEAD}{body}    }}\n}}\n");
    read_skeleton(&parse_usda(&text).unwrap(), "/R/S")
        .unwrap_err()
        .to_string()
}

#[test]
fn a_skeleton_without_joints_is_an_error_naming_it() {
    let e = skeleton_error(
        "        uniform token[] joints = []\n        uniform matrix4d[] bindTransforms = []\n",
    );
    assert!(
        e.contains("Skeleton '/R/S'") && e.contains("no joints"),
        "{e}"
    );
}

#[test]
fn an_animation_naming_a_missing_joint_is_an_error() {
    let e = skeleton_error(concat!(
        "        uniform token[] joints = [\"A\"]\n",
        "        uniform matrix4d[] bindTransforms = [((1,0,0,0),(0,1,0,0),(0,0,1,0),(0,0,0,1))]\n",
        "        rel skel:animationSource = </R/S/Anim>\n",
        "        def SkelAnimation \"Anim\"\n        {\n",
        "            uniform token[] joints = [\"A/Nope\"]\n",
        "            float3[] translations = [(0,0,0)]\n",
        "            quatf[] rotations = [(1,0,0,0)]\n",
        "        }\n"
    ));
    assert!(
        e.contains("'A/Nope'") && e.contains("'/R/S/Anim'") && e.contains("'/R/S'"),
        "{e}"
    );
}

fn arm_with(replace: &str, by: &str) -> String {
    let text = std::fs::read_to_string(asset("assets/course/arm.usda")).unwrap();
    assert!(text.contains(replace));
    text.replacen(replace, by, 1)
}

#[test]
fn weights_and_indices_of_different_lengths_are_an_error_naming_the_mesh() {
    let text = arm_with("1,1,1,1, 1,1,1,1, 1,1,1,1", "1,1,1,1, 1,1,1,1, 1,1,1");
    let e = read_usda(&text, "/Model/Mesh", true)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("'/Model/Mesh'") && e.contains("11 jointWeights but 12 jointIndices"),
        "{e}"
    );
}

#[test]
fn a_joint_index_out_of_range_is_an_error_naming_the_skeleton() {
    let text = arm_with("2,2,2,2, 0,0,0,0", "2,2,2,7, 0,0,0,0");
    let e = read_usda(&text, "/Model/Mesh", true)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("= 7 is out of range") && e.contains("'/Model/Skel'"),
        "{e}"
    );
}

#[test]
fn weights_not_adding_to_one_are_normalized_with_a_warning() {
    let text = arm_with("1,1,1,1, 1,1,1,1, 1,1,1,1", "2,2,2,2, 1,1,1,1, 1,1,1,1");
    let m = read_usda(&text, "/Model/Mesh", true).unwrap();
    let reference = load("assets/course/arm.usda", "/Model/Mesh");
    let s = skin_mesh(&m, None, 5.0, SkinMethod::Lbs).unwrap();
    let want = skin_mesh(&reference, None, 5.0, SkinMethod::Lbs).unwrap();
    assert_eq!(s.mesh.positions, want.mesh.positions);
    assert!(
        s.warnings
            .iter()
            .any(|w| w.starts_with("warning:") && w.contains("4 of 12")),
        "{:?}",
        s.warnings
    );
    assert!(want.warnings.is_empty());
}

#[test]
fn a_singular_bind_transform_and_a_missing_binding_are_errors() {
    let text = arm_with(
        "((1,0,0,0),(0,1,0,0),(0,0,1,0),(0,0,2,1)),",
        "((0,0,0,0),(0,0,0,0),(0,0,0,0),(0,0,2,1)),",
    );
    let m = read_usda(&text, "/Model/Mesh", false).unwrap();
    let e = skin_mesh(&m, None, 1.0, SkinMethod::Lbs)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("'Shoulder/Elbow'") && e.contains("'/Model/Skel'") && e.contains("mesh"),
        "{e}"
    );
    let plain = load("assets/course/sphere.usda", "");
    let e = skin_mesh(&plain, None, 1.0, SkinMethod::Dqs)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no skeleton binding") && e.contains("mesh"),
        "{e}"
    );
}

#[test]
fn the_blender_arm_loads_with_its_binding_and_matches_the_course_arm() {
    // arm_with_cloth.usda is arm.usda re-exported by Blender with a cloth grid and denser
    // animation; at time 1 both are at rest.
    let a = load("assets/course/arm_with_cloth.usda", "/root/Model/Mesh/Mesh");
    let b = a.skin.as_deref().unwrap();
    assert_eq!((b.influences, b.skeleton.joints.len()), (2, 3));
    let s = skin_mesh(&a, None, 1.0, SkinMethod::Lbs).unwrap().mesh;
    for (p, q) in s.positions.iter().zip(&a.positions) {
        for k in 0..3 {
            assert!((p[k] - q[k]).abs() < 1e-6, "{p:?} {q:?}");
        }
    }
}
