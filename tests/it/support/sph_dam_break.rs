//! The Martin & Moyce (1952) dam break in 2-D, shared by `tests/it/sph.rs` and `bench/sph.rs`
//! (included with `#[path]`; `graphs/dam_break_2d.json` builds the same case from nodes): a
//! column `a` wide and `2a` high (n^2 = 2) against the left wall of a tank `4a` long, and the
//! comparison of the surge front with the experiment in its dimensionless units `Z = z / a`,
//! `T = n t sqrt(g / a)`.

use cgnodes::nodes::metrics::compare_series::read_csv_columns;
use cgnodes::nodes::sim::sph::{Boundary, Fluid, Solver, SphParams};

/// The experiment's surge front `(T, Z)` for the `a x 2a` column (n^2 = 2):
/// `tests/data/sph/martin_moyce_front.csv` holds only that series (its `quantity` is `front`
/// and its `n2` is 2 on every row).
pub fn martin_moyce_front() -> Vec<(f64, f64)> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/sph/martin_moyce_front.csv"
    );
    let text = std::fs::read_to_string(path).unwrap();
    read_csv_columns(&text, "T_or_tau", "Z_or_H").unwrap()
}

/// The dam-break fluid: column `a x 2a` in a tank `4a x 2.5a`, particle radius `r`.
pub fn setup(solver: Solver, a: f64, r: f64, viscosity: f64) -> Result<Fluid, String> {
    let g = 9.81;
    let prm = SphParams {
        dim: 2,
        solver,
        boundary: Boundary::Particles,
        box_min: [0.0; 3],
        box_max: [4.0 * a, 2.5 * a, 0.0],
        particle_radius: r,
        viscosity,
        gravity: -g,
        dt: 0.005,
        cfl: 0.4,
        // WCSPH: sound speed 10x the largest flow speed sqrt(2 g 2a) (Monaghan 1994's rule).
        stiffness: 1000.0 * 100.0 * 2.0 * g * 2.0 * a / 7.0,
        ..Default::default()
    };
    Fluid::block(prm, [0.0; 3], [a, 2.0 * a, 0.0], None).map_err(|e| e.to_string())
}

/// Runs `f` (from `setup`) up to `T = t_end`, sampling the front every `sample` seconds;
/// returns `(T, Z)` with `a` and the height measured from the initial column.
pub fn run(f: &mut Fluid, t_end: f64, sample: f64) -> Result<Vec<(f64, f64)>, String> {
    let a0 = f.front();
    let n = (f.height() / a0).sqrt();
    let ts = n * (f.params.gravity.abs() / a0).sqrt();
    let mut hist = vec![(0.0, 1.0)];
    while f.time * ts < t_end {
        f.advance(sample).map_err(|e| e.to_string())?;
        hist.push((f.time * ts, f.front() / a0));
    }
    Ok(hist)
}

/// Relative errors `(T_sim(Z) - T_exp) / T_exp` at the experiment's points with
/// `Z >= 1.44` reached by the simulation, after shifting the simulated time so that
/// `T = 1.19` at `Z = 1.44` (Martin & Moyce's own anchor). `T_sim(Z)` is interpolated at the
/// first crossing. Returns `(T_exp, relative error)` pairs.
pub fn anchored_errors(sim: &[(f64, f64)], exp: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let t_at = |z: f64| -> Option<f64> {
        sim.windows(2).find(|w| w[0].1 < z && w[1].1 >= z).map(|w| {
            let u = (z - w[0].1) / (w[1].1 - w[0].1);
            w[0].0 + u * (w[1].0 - w[0].0)
        })
    };
    let Some(t144) = t_at(1.44) else {
        return Vec::new();
    };
    let shift = 1.19 - t144;
    exp.iter()
        .filter(|(_, z)| *z >= 1.44)
        .filter_map(|&(t, z)| t_at(z).map(|ts| (t, (ts + shift - t) / t)))
        .collect()
}

/// Root mean square of the relative errors.
pub fn rms(errors: &[(f64, f64)]) -> f64 {
    if errors.is_empty() {
        return f64::NAN;
    }
    (errors.iter().map(|e| e.1 * e.1).sum::<f64>() / errors.len() as f64).sqrt()
}
