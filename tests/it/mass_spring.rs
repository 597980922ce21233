//! `mass_spring` against analytic references (`tests/data/springs/analytic_checks.json`, from
//! the shared reference folder): single-spring period and energy, the symplectic stability
//! limit 2/omega_max on an 8x8 grid, implicit stability far beyond it, fixed vertices, the
//! sphere collider, and degenerate models (the node in graphs: `tests/it/mass_spring_node.rs`).

use cgnodes::nodes::mesh::mesh_grid::grid_mesh;
use cgnodes::nodes::sim::mass_spring::{
    springs_from_mesh, Method, Model, SimError, Simulator, SolverOptions, Sphere, SpringKinds,
    Springs,
};
use cgnodes::types::Mesh;
use std::collections::BTreeSet;
use std::path::Path;

use crate::support::hanging_cloth;
use hanging_cloth::{course_cloth, hanging};

fn reference() -> serde_json::Value {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/springs/analytic_checks.json");
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// One spring along x, vertex 0 fixed at the origin, vertex 1 of mass m displaced by `x0`
/// from the rest length `L = 10` (long, so the motion stays far from zero length and the
/// dynamics along x are exactly `x'' = -(k/m) x`).
fn single_spring(method: Method, dt: f64) -> Simulator {
    let (m, k, l0) = (1.0, 100.0, 10.0);
    let x = vec![[0.0, 0.0, 0.0], [l0, 0.0, 0.0]];
    let mut springs = Springs::default();
    springs.push(0, 1, &x, k);
    let model = Model {
        springs,
        mass: vec![m, m],
        fixed: vec![true, false],
        gravity: [0.0; 3],
        damping: 1.0,
    };
    let x0 = vec![[0.0, 0.0, 0.0], [l0 + 1.0, 0.0, 0.0]];
    Simulator::new(model, x0, None, method, dt, SolverOptions::default()).unwrap()
}

/// Runs the single spring for 100 periods; returns (measured period, max |E/E0 - 1|, E_end/E0).
fn spring_run(method: Method, dt: f64) -> (f64, f64, f64) {
    let period = 2.0 * std::f64::consts::PI * (1.0f64 / 100.0).sqrt();
    let n = (100.0 * period / dt).round() as usize;
    let mut sim = single_spring(method, dt);
    let e0 = sim.energy(None).total();
    let mut xs = vec![1.0];
    let mut dev: f64 = 0.0;
    let mut e_end = e0;
    for _ in 0..n {
        let l = sim.step(None).unwrap();
        xs.push(sim.state.x[1][0] - 10.0);
        e_end = l.energy.total();
        dev = dev.max((e_end / e0 - 1.0).abs());
    }
    let mut tc = Vec::new();
    for i in 0..n {
        if xs[i] < 0.0 && xs[i + 1] >= 0.0 {
            tc.push((i as f64 + (-xs[i]) / (xs[i + 1] - xs[i])) * dt);
        }
    }
    let p = (tc[tc.len() - 1] - tc[0]) / (tc.len() - 1) as f64;
    (p, dev, e_end / e0)
}

#[test]
fn single_spring_period_matches_discrete_formula_and_converges() {
    let r = reference();
    let exact = 2.0 * std::f64::consts::PI * (1.0f64 / 100.0).sqrt();
    let mut errs = Vec::new();
    for case in r["single_spring"]["symplectic"].as_array().unwrap() {
        let dt = case["dt"].as_f64().unwrap();
        let (p, dev, ratio) = spring_run(Method::SemiImplicit, dt);
        // Discrete period of symplectic Euler: 2 pi dt / acos(1 - (omega dt)^2 / 2).
        let w = 10.0;
        let discrete = 2.0 * std::f64::consts::PI * dt / (1.0 - (w * dt) * (w * dt) / 2.0).acos();
        let ref_disc = case["period_theory_discrete"].as_f64().unwrap();
        assert!((discrete - ref_disc).abs() < 1e-12 * ref_disc);
        assert!(
            (p - discrete).abs() < 1e-7 * discrete,
            "dt {dt}: period {p} vs discrete {discrete}"
        );
        let ref_meas = case["period_measured"].as_f64().unwrap();
        assert!(
            (p - ref_meas).abs() < 1e-7 * ref_meas,
            "{p} vs reference {ref_meas}"
        );
        // Bounded energy (symplectic): same oscillation amplitude as the reference.
        let ref_dev = case["E_max_rel_dev"].as_f64().unwrap();
        assert!(
            (dev - ref_dev).abs() < 1e-3 * ref_dev,
            "dt {dt}: energy deviation {dev} vs reference {ref_dev}"
        );
        let ref_ratio = case["E_final_over_E0"].as_f64().unwrap();
        assert!((ratio - ref_ratio).abs() < 1e-6, "{ratio} vs {ref_ratio}");
        errs.push((p - exact).abs() / exact);
    }
    // Converges to 2 pi sqrt(m/k) at second order: 10x smaller dt, ~100x smaller error.
    assert!(errs[1] < 1e-5, "period error {} at dt = 0.001", errs[1]);
    assert!(errs[0] / errs[1] > 80.0, "errors {errs:?}");
}

#[test]
fn symplectic_energy_stays_bounded_over_many_periods() {
    // omega dt = 0.5 for ~800 periods. Symplectic Euler conserves a modified energy, so the
    // true energy (sampled at x_{n+1}, v_{n+1}) oscillates without drift; its largest relative
    // deviation is omega dt / (2 - omega dt), which the reference's 0.0526 (omega dt = 0.1)
    // and 0.0050 (omega dt = 0.01) also follow.
    let wdt: f64 = 0.5;
    let bound = wdt / (2.0 - wdt);
    let (_, dev, ratio) = spring_run(Method::SemiImplicit, 0.05);
    assert!(
        dev <= bound * (1.0 + 1e-6),
        "energy deviation {dev} > {bound}"
    );
    assert!(
        dev > 0.9 * bound,
        "energy deviation {dev} (expected about {bound})"
    );
    assert!((ratio - 1.0).abs() <= bound * (1.0 + 1e-6));
    let r = reference();
    let cases = r["single_spring"]["symplectic"].as_array().unwrap();
    assert_eq!(cases.len(), 2, "the reference's two symplectic runs");
    for case in cases {
        let wdt = case["omega_dt"].as_f64().unwrap();
        let d = case["E_max_rel_dev"].as_f64().unwrap();
        assert!((d - wdt / (2.0 - wdt)).abs() < 1e-6 * d);
    }
}

/// The reference 8x8 grid: spacing 0.1, structural + shear + skip-one bending springs.
fn grid8() -> (Mesh, Springs) {
    let mesh = grid_mesh(7, 7, [0.7, 0.7], "xy", [0.35, 0.35, 0.0], false).unwrap();
    let kinds = SpringKinds {
        shear: true,
        bending: true,
        bending_scale: 1.0,
    };
    let s = springs_from_mesh(&mesh, 1000.0, kinds);
    (mesh, s)
}

fn grid8_model(fixed: &[usize], gravity: f64) -> (Model, Vec<[f64; 3]>) {
    let (mesh, springs) = grid8();
    let n = mesh.num_vertices();
    let mut f = vec![false; n];
    for &i in fixed {
        f[i] = true;
    }
    let model = Model {
        springs,
        mass: vec![0.01; n],
        fixed: f,
        gravity: [0.0, 0.0, gravity],
        damping: 1.0,
    };
    // Deterministic 1e-4 perturbation (xorshift), as the reference perturbs its grid.
    let mut s = 0x9E3779B97F4A7C15u64;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let x0 = mesh
        .positions
        .iter()
        .map(|p| {
            [
                p[0] + 1e-4 * rnd(),
                p[1] + 1e-4 * rnd(),
                p[2] + 1e-4 * rnd(),
            ]
        })
        .collect();
    (model, x0)
}

#[test]
fn grid_springs_match_reference_and_omega_max() {
    let r = &reference()["grid_8x8_struct_shear_bend"];
    let (mesh, s) = grid8();
    assert_eq!(s.len() as u64, r["springs"].as_u64().unwrap());
    // Same spring set as the reference script builds.
    let mut want = BTreeSet::new();
    for j in 0..8u32 {
        for i in 0..8u32 {
            let a = j * 8 + i;
            let mut add = |p: u32, q: u32| {
                want.insert((p.min(q), p.max(q)));
            };
            if i + 1 < 8 {
                add(a, a + 1);
            }
            if j + 1 < 8 {
                add(a, a + 8);
            }
            if i + 1 < 8 && j + 1 < 8 {
                add(a, a + 9);
                add(a + 1, a + 8);
            }
            if i + 2 < 8 {
                add(a, a + 2);
            }
            if j + 2 < 8 {
                add(a, a + 16);
            }
        }
    }
    let got: BTreeSet<(u32, u32)> = s.ends.iter().map(|e| (e[0], e[1])).collect();
    assert_eq!(got, want);
    // omega_max from the dense stiffness matrix at rest.
    let n = mesh.num_vertices();
    let mut k = nalgebra::DMatrix::<f64>::zeros(3 * n, 3 * n);
    for (si, e) in s.ends.iter().enumerate() {
        let (a, b) = (e[0] as usize, e[1] as usize);
        let d: Vec<f64> = (0..3)
            .map(|c| mesh.positions[b][c] - mesh.positions[a][c])
            .collect();
        let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        for p in 0..3 {
            for q in 0..3 {
                let v = s.k[si] * d[p] * d[q] / (l * l);
                k[(3 * a + p, 3 * a + q)] += v;
                k[(3 * b + p, 3 * b + q)] += v;
                k[(3 * a + p, 3 * b + q)] -= v;
                k[(3 * b + p, 3 * a + q)] -= v;
            }
        }
    }
    let lmax = k.symmetric_eigenvalues().max() / 0.01;
    let w = r["omega_max"].as_f64().unwrap();
    assert!((lmax.sqrt() - w).abs() < 1e-8 * w, "{} vs {w}", lmax.sqrt());
}

#[test]
fn symplectic_stability_limit_on_8x8_grid() {
    let r = &reference()["grid_8x8_struct_shear_bend"];
    let dtc = r["dt_crit_2_over_omega_max"].as_f64().unwrap();
    assert_eq!(r["run_1p05_dtcrit"], "blew up");
    for (factor, bounded) in [(0.95, true), (1.05, false)] {
        let (model, x0) = grid8_model(&[], 0.0);
        let rest = model.springs.clone();
        let mut sim = Simulator::new(
            model,
            x0,
            None,
            Method::SemiImplicit,
            factor * dtc,
            SolverOptions::default(),
        )
        .unwrap();
        let mut outcome = Ok(());
        for _ in 0..4000 {
            if let Err(e) = sim.step(None) {
                outcome = Err(e);
                break;
            }
        }
        if bounded {
            assert!(outcome.is_ok(), "{factor}x: {outcome:?}");
            let (mesh, _) = grid8();
            let dx = sim
                .state
                .x
                .iter()
                .zip(&mesh.positions)
                .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
                .fold(0.0, f64::max);
            // The reference reports 1.3e-3 for its own random perturbation.
            assert!(dx < 1e-2, "0.95x drifted by {dx}");
            assert_eq!(rest.len(), 306);
        } else {
            match outcome {
                Err(SimError::Unstable { step, .. }) => assert!(step > 0 && step < 4000),
                other => panic!("1.05x was not reported unstable: {other:?}"),
            }
        }
    }
}

#[test]
fn implicit_and_projective_stay_bounded_at_50x_the_limit() {
    let r = &reference()["grid_8x8_struct_shear_bend"];
    let h = 50.0 * r["dt_crit_2_over_omega_max"].as_f64().unwrap();
    for method in [Method::Implicit, Method::Projective] {
        // Free grid, no gravity: the perturbation's energy must not grow.
        let (model, x0) = grid8_model(&[], 0.0);
        let mut sim = Simulator::new(model, x0, None, method, h, SolverOptions::default()).unwrap();
        let e0 = sim.energy(None).total();
        for _ in 0..100 {
            let l = sim.step(None).unwrap();
            assert!(
                l.energy.total() <= e0 * (1.0 + 1e-9) + 1e-12,
                "{method:?} gained energy"
            );
        }
        // Hanging from two corners under gravity: bounded, corners exact.
        let (model, x0) = grid8_model(&[56, 63], -9.8);
        let corners = [x0[56], x0[63]];
        let mut sim = Simulator::new(model, x0, None, method, h, SolverOptions::default()).unwrap();
        let mut strain: f64 = 0.0;
        for _ in 0..100 {
            let l = sim.step(None).unwrap();
            strain = strain.max(l.energy.max_strain);
        }
        assert!(strain < 0.5, "{method:?}: max strain {strain}");
        assert_eq!([sim.state.x[56], sim.state.x[63]], corners);
    }
    // At the same step symplectic Euler blows up immediately.
    let (model, x0) = grid8_model(&[], 0.0);
    let mut sim = Simulator::new(
        model,
        x0,
        None,
        Method::SemiImplicit,
        h,
        SolverOptions::default(),
    )
    .unwrap();
    assert!((0..100).any(|_| sim.step(None).is_err()));
}

#[test]
fn implicit_reuses_its_symbolic_factorization() {
    let (model, x0) = grid8_model(&[56, 63], -9.8);
    let mut sim = Simulator::new(
        model,
        x0,
        None,
        Method::Implicit,
        0.01,
        SolverOptions::default(),
    )
    .unwrap();
    for _ in 0..20 {
        let l = sim.step(None).unwrap();
        assert!(l.iterations >= 1 && l.iterations <= 20);
    }
    let (sym, num) = sim.factorizations().unwrap();
    assert_eq!(sym, 1);
    assert!(num >= 20);
}

#[test]
fn fixed_vertices_do_not_move() {
    for (method, h, steps) in [
        (Method::SemiImplicit, 5e-4, 600),
        (Method::Implicit, 0.01, 30),
        (Method::Projective, 0.01, 30),
    ] {
        let (mut sim, fixed) = hanging(method, h);
        let x0: Vec<[f64; 3]> = fixed.iter().map(|&i| sim.state.x[i]).collect();
        let mut fell = 0.0;
        for _ in 0..steps {
            sim.step(None).unwrap();
        }
        for (k, &i) in fixed.iter().enumerate() {
            assert_eq!(sim.state.x[i], x0[k], "{method:?} moved fixed vertex {i}");
            assert_eq!(sim.state.v[i], [0.0; 3]);
        }
        for p in &sim.state.x {
            fell = f64::min(fell, p[2]);
        }
        assert!(fell < -0.05, "{method:?}: the cloth did not fall ({fell})");
    }
}

#[test]
fn no_vertex_ends_inside_the_sphere() {
    let sphere = Sphere {
        center: [0.0, 0.0, -1.0],
        radius: 0.4,
        k: 10000.0,
        scale: 1.1,
    };
    for (method, h, steps) in [
        (Method::SemiImplicit, 5e-4, 1600),
        (Method::Implicit, 0.01, 80),
        (Method::Projective, 0.01, 80),
    ] {
        let mesh = grid_mesh(10, 10, [1.6, 1.6], "xy", [0.0; 3], true).unwrap();
        let mut sim = course_cloth(&mesh, vec![false; mesh.num_vertices()], method, h);
        let mut dmin = f64::INFINITY;
        for _ in 0..steps {
            sim.step(Some(&sphere)).unwrap();
            for p in &sim.state.x {
                let d = ((p[0]) * p[0] + p[1] * p[1] + (p[2] + 1.0) * (p[2] + 1.0)).sqrt();
                dmin = dmin.min(d);
            }
        }
        // Penalty contact starts at 1.1 r: the cloth must touch that shell but never reach
        // the sphere itself (the 0.1 r shell is the penalty's tolerance).
        assert!(dmin > sphere.radius, "{method:?}: a vertex reached {dmin}");
        assert!(
            dmin < sphere.contact_radius() + 1e-3,
            "{method:?}: the cloth never touched the sphere ({dmin})"
        );
        // The centre vertex rests on top of the sphere.
        let c = sim.state.x[60];
        assert!(
            (c[2] + 1.0 - sphere.contact_radius()).abs() < 0.02,
            "{method:?}: {c:?}"
        );
    }
}

#[test]
fn degenerate_models_fail_cleanly_or_do_nothing() {
    let mesh = grid_mesh(2, 2, [1.0, 1.0], "xy", [0.0; 3], true).unwrap();
    let n = mesh.num_vertices();
    for method in [Method::SemiImplicit, Method::Implicit, Method::Projective] {
        // Every vertex fixed: nothing to solve, nothing moves.
        let model = Model {
            springs: springs_from_mesh(&mesh, 1000.0, SpringKinds::default()),
            mass: vec![0.1; n],
            fixed: vec![true; n],
            gravity: [0.0, 0.0, -9.8],
            damping: 1.0,
        };
        let mut sim = Simulator::new(
            model.clone(),
            mesh.positions.clone(),
            None,
            method,
            0.01,
            SolverOptions::default(),
        )
        .unwrap();
        sim.step(None).unwrap();
        assert_eq!(sim.state.x, mesh.positions);
        // Coincident vertices (zero rest length) and zero mass are input errors.
        let mut x = mesh.positions.clone();
        x[1] = x[0];
        let mut bad = model.clone();
        bad.springs = springs_from_mesh(
            &Mesh::new(
                x.clone(),
                mesh.face_counts().to_vec(),
                mesh.face_indices().to_vec(),
            )
            .unwrap(),
            1000.0,
            SpringKinds::default(),
        );
        assert!(Simulator::new(bad, x, None, method, 0.01, SolverOptions::default()).is_err());
        let mut bad = model.clone();
        bad.mass[0] = 0.0;
        assert!(Simulator::new(
            bad,
            mesh.positions.clone(),
            None,
            method,
            0.01,
            SolverOptions::default()
        )
        .is_err());
    }
}
