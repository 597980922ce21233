//! The `mass_spring` node in graphs run by the executor: state kept across frames, blow-ups
//! reported with frame and step, and bad fixed-vertex selections rejected as input errors.
//! The simulator itself is checked in `tests/it/mass_spring.rs`.

use crate::support::hanging_cloth;

use cgnodes::node::{ErrorKind, FileEnv};
use cgnodes::nodes::mesh::mesh_grid::grid_mesh;
use cgnodes::nodes::sim::mass_spring::Method;
use cgnodes::registry::Registry;
use cgnodes::types::{Mesh, Value};
use hanging_cloth::hanging;

fn run_graph(json: &str, frames: std::ops::RangeInclusive<i64>) -> Vec<cgnodes::exec::RunReport> {
    let dir = tempfile::tempdir().unwrap();
    let r = cgnodes::nodes::builtin_registry();
    crate::common::run_graph(json, &r, dir.path(), &dir.path().join("out"), 1, frames)
}

const GRAPH: &str = r#"{
  "format": "cgnodes-graph", "version": 1,
  "nodes": {
    "grid": {"type": "mesh_grid", "params": {"cells_u": 10, "cells_v": 10}},
    "sim": {"type": "mass_spring", "inputs": {"mesh": "grid.mesh"},
            "params": {"integrator": "INTEGRATOR", "h": H, "substeps": SUB, "fixed": "top_corners"}},
    "save": {"type": "mesh_save", "inputs": {"mesh": "sim.mesh"}, "params": {"path": "cloth_{frame:04}.obj"}}
  }
}"#;

fn graph(integrator: &str, h: f64, substeps: i64) -> String {
    GRAPH
        .replace("INTEGRATOR", integrator)
        .replace("H", &h.to_string())
        .replace("SUB", &substeps.to_string())
}

fn output_mesh(r: &cgnodes::exec::RunReport) -> std::sync::Arc<Mesh> {
    match r.output("sim", "mesh") {
        Some(Value::Mesh(m)) => m.clone(),
        other => panic!("no mesh: {other:?} {:?}", r.errors()),
    }
}

#[test]
fn executor_keeps_state_across_frames() {
    let reports = run_graph(&graph("implicit", 0.01, 2), 1..=5);
    for r in &reports {
        assert!(r.ok(), "{:?}", r.errors());
    }
    // Frame 1 is the rest state; frames 2..5 each advance 2 steps of 0.01.
    let (mut sim, _) = hanging(Method::Implicit, 0.01);
    assert_eq!(output_mesh(&reports[0]).positions, sim.state.x);
    for (f, r) in reports.iter().enumerate().skip(1) {
        for _ in 0..2 {
            sim.step(None).unwrap();
        }
        let m = output_mesh(r);
        assert_eq!(m.positions.len(), sim.state.x.len(), "frame {}", f + 1);
        let err = m
            .positions
            .iter()
            .zip(&sim.state.x)
            .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
            .fold(0.0, f64::max);
        assert!(
            err < 1e-9,
            "frame {}: differs from a direct run by {err}",
            f + 1
        );
        match r.output("sim", "log") {
            Some(Value::Table(t)) => {
                assert_eq!(t.num_rows(), 2);
                assert_eq!(
                    t.column("step").unwrap(),
                    &[(2 * f - 1) as f64, (2 * f) as f64]
                );
            }
            other => panic!("no log: {other:?}"),
        }
    }
    // The cloth has moved by the last frame.
    assert_ne!(
        output_mesh(&reports[4]).positions,
        output_mesh(&reports[0]).positions
    );
}

#[test]
fn explicit_blow_up_is_reported_with_frame_and_step() {
    // The course default h = 0.01 is far beyond semi-implicit's limit on a 10x10 grid.
    let reports = run_graph(&graph("semi_implicit", 0.01, 10), 1..=4);
    let err = reports
        .iter()
        .flat_map(|r| r.nodes.iter())
        .find_map(|n| match &n.status {
            cgnodes::exec::NodeStatus::Failed(e) => Some(e.clone()),
            _ => None,
        })
        .expect("semi-implicit at h = 0.01 must fail");
    assert_eq!(err.kind, ErrorKind::Unstable);
    assert!(
        err.message.contains("frame") && err.message.contains("step"),
        "{}",
        err.message
    );
}

#[test]
fn bad_fixed_selection_is_an_input_error() {
    let mut r = Registry::new();
    cgnodes::nodes::sim::mass_spring::register(&mut r);
    let decl = r.get("mass_spring").unwrap();
    let mesh = grid_mesh(3, 3, [1.0, 1.0], "xy", [0.0; 3], true).unwrap();
    for sel in ["999", "left_ear", "attr:missing"] {
        let mut inputs = std::collections::BTreeMap::new();
        inputs.insert("mesh".to_string(), Value::from(mesh.clone()));
        inputs.insert("fixed".to_string(), Value::from(sel));
        let mut state = None;
        let files = FileEnv::default();
        let mut ctx = cgnodes::node::ExecContext::standalone(decl, inputs, &mut state, &files, 0);
        let e = (decl.exec.as_ref().unwrap())(&mut ctx).unwrap_err();
        assert_eq!(e.kind, ErrorKind::InvalidInput, "{sel}: {e}");
    }
}

const CONTROL: &str = r#"{
  "format": "cgnodes-graph", "version": 1,
  "nodes": {
    "grid": {"type": "mesh_grid", "params": {"cells_u": 6, "cells_v": 6}},
    "t": {"type": "frame"},
    "d": {"type": "math", "params": {"op": "mul", "b": SPEED}, "inputs": {"a": "t.time"}},
    "body": {"type": "mesh_transform", "inputs": {"mesh": "grid.mesh", "translate": "d.value"}},
    "sim": {"type": "mass_spring", "inputs": {"mesh": "grid.mesh" CONTROL_LINK},
            "params": {"integrator": "INTEGRATOR", "h": STEP, "substeps": 3, "fixed": "top_corners"}},
    "save": {"type": "mesh_save", "inputs": {"mesh": "sim.mesh"}, "params": {"path": "c_{frame:04}.obj"}}
  }
}"#;

fn control_graph(integrator: &str, speed: f64, linked: bool) -> String {
    // the explicit integrator needs a smaller step to stay stable at the default stiffness
    let step = if integrator == "semi_implicit" {
        "0.001"
    } else {
        "0.01"
    };
    CONTROL
        .replace("STEP", step)
        .replace("INTEGRATOR", integrator)
        .replace("SPEED", &speed.to_string())
        .replace(
            "CONTROL_LINK",
            if linked {
                r#", "control_mesh": "body.mesh""#
            } else {
                ""
            },
        )
}

/// Control points: the fixed corners pair with themselves on a body that starts as the
/// cloth, then follow it exactly while it moves (all four integrators); a body that stays
/// put gives the same run as plain fixed vertices.
#[test]
fn fixed_vertices_follow_the_control_mesh() {
    for integrator in ["implicit", "semi_implicit", "projective", "quasi_newton"] {
        let plain = run_graph(&control_graph(integrator, 0.05, false), 0..=3);
        // Frame 0 is the rest state: the grid itself.
        let grid = output_mesh(&plain[0]);
        let still = run_graph(&control_graph(integrator, 0.0, true), 0..=3);
        let moving = run_graph(&control_graph(integrator, 0.05, true), 0..=3);
        let last = output_mesh(&plain[3]);
        let fixed: Vec<usize> = (0..grid.positions.len())
            .filter(|&i| last.positions[i] == grid.positions[i])
            .collect();
        assert_eq!(fixed.len(), 2, "{integrator}: top corners");
        for f in 0..=3usize {
            assert!(moving[f].ok(), "{:?}", moving[f].errors());
            assert_eq!(
                output_mesh(&still[f]).positions,
                output_mesh(&plain[f]).positions,
                "{integrator} frame {f}: a still body changes nothing"
            );
            let m = output_mesh(&moving[f]);
            for &i in &fixed {
                let want: [f64; 3] =
                    std::array::from_fn(|c| grid.positions[i][c] + f as f64 * 0.05);
                let d = (0..3)
                    .map(|c| (m.positions[i][c] - want[c]).abs())
                    .fold(0.0, f64::max);
                assert!(d < 1e-12, "{integrator} frame {f} vertex {i}: off by {d}");
            }
            // The free cloth is dragged along: its centre moves towards +x, +y, +z too.
            if f == 3 {
                let c = |p: &[[f64; 3]]| p.iter().map(|x| x[0]).sum::<f64>() / p.len() as f64;
                assert!(c(&m.positions) > c(&output_mesh(&plain[f]).positions));
            }
        }
    }
}

#[test]
fn control_pairs_need_a_control_mesh_and_valid_indices() {
    let bad = CONTROL
        .replace("STEP", "0.01")
        .replace("INTEGRATOR", "implicit")
        .replace("SPEED", "0.1")
        .replace("CONTROL_LINK", "")
        .replace(r#""fixed": "top_corners""#, r#""control_pairs": [0, 0]"#);
    let r = run_graph(&bad, 0..=0);
    let e = format!("{:?}", r[0].errors());
    assert!(e.contains("control_pairs"), "{e}");
    let bad = control_graph("implicit", 0.1, true)
        .replace(r#""fixed": "top_corners""#, r#""control_pairs": [0, 49]"#);
    let r = run_graph(&bad, 0..=0);
    let e = format!("{:?}", r[0].errors());
    assert!(e.contains("body vertex 49"), "{e}");
}
