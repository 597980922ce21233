//! Divergence-free SPH (Bender & Koschier 2015, "Divergence-Free Smoothed Particle
//! Hydrodynamics"; 2017, "Divergence-Free SPH for Incompressible and Viscous Fluids",
//! Alg. 1): per step, a divergence-free solver makes `D rho / Dt = 0`, the non-pressure
//! forces are applied, and a constant-density solver makes the predicted density equal the
//! rest density; both are Jacobi iterations that update velocities only, so the neighbour
//! lists and kernel gradients of the step are reused by every iteration.
//!
//! Written in density ratios `rho^_i = rho_i / rho0` and volumes `V = m / rho0`. A velocity
//! update with stiffness values `kappa` is
//! `v_i -= dt (sum_j V (kappa_i + kappa_j) grad W_ij + sum_b V_b 2 kappa_i grad W_ib)`
//! (the SPH pressure acceleration with `kappa = rho0 p / rho^2`; boundary particles mirror
//! `kappa_i`). Changing only `kappa_i` changes `rho^*_i` by `-dt^2 kappa_i / alpha_i` with
//! the DFSPH factor (Bender & Koschier 2017 eq. 8, in these units)
//! `1/alpha_i = g'_i . g_i + V^2 sum_j |grad W_ij|^2`,
//! `g_i = sum_j V grad W_ij + sum_b V_b grad W_ib`, `g'_i = sum_j V grad W_ij + 2 sum_b V_b grad W_ib`.

use super::neighbour_grid::GridError;
use super::pressure_solver::PressureSolver;
use super::state::{Fluid, StepStats};
use cgnodes_api::types::vec3::{axpy, dot, sub};
use rayon::prelude::*;

/// `alpha_i` (see the module doc); 0 for particles without neighbours.
fn factors(f: &Fluid, vol: f64) -> Vec<f64> {
    let bvol = &f.boundary_volumes;
    let tiny = 1e-6 / (f.kernel.h * f.kernel.h);
    f.fluid_neighbours
        .par_iter()
        .zip(f.boundary_neighbours.par_iter())
        .map(|(nf, nb)| {
            let mut gf = [0.0; 3];
            let mut gb = [0.0; 3];
            let mut sq = 0.0;
            for n in nf {
                gf = axpy(gf, vol, n.grad_w);
                sq += dot(n.grad_w, n.grad_w);
            }
            for n in nb {
                gb = axpy(gb, bvol[n.index as usize], n.grad_w);
            }
            let g = [gf[0] + gb[0], gf[1] + gb[1], gf[2] + gb[2]];
            let g2 = [g[0] + gb[0], g[1] + gb[1], g[2] + gb[2]];
            let s = dot(g2, g) + vol * vol * sq;
            if s > tiny {
                1.0 / s
            } else {
                0.0
            }
        })
        .collect()
}

/// `D rho^_i / Dt = sum_j V (v_i - v_j) . grad W_ij + sum_b V_b v_i . grad W_ib`.
fn density_rate(f: &Fluid, vol: f64) -> Vec<f64> {
    let (v, bvol) = (&f.velocities, &f.boundary_volumes);
    f.fluid_neighbours
        .par_iter()
        .zip(f.boundary_neighbours.par_iter())
        .enumerate()
        .map(|(i, (nf, nb))| {
            let mut s = 0.0;
            for n in nf {
                let vij = sub(v[i], v[n.index as usize]);
                s += vol * dot(vij, n.grad_w);
            }
            for n in nb {
                s += bvol[n.index as usize] * dot(v[i], n.grad_w);
            }
            s
        })
        .collect()
}

/// `v_i -= dt (sum_j V (kappa_i + kappa_j) grad W_ij + sum_b V_b 2 kappa_i grad W_ib)`.
fn apply_kappa(f: &mut Fluid, kappa: &[f64], vol: f64, dt: f64) {
    let (nbf, nbb, bvol) = (
        &f.fluid_neighbours,
        &f.boundary_neighbours,
        &f.boundary_volumes,
    );
    f.velocities.par_iter_mut().enumerate().for_each(|(i, v)| {
        let ki = kappa[i];
        for n in &nbf[i] {
            *v = axpy(*v, -dt * vol * (ki + kappa[n.index as usize]), n.grad_w);
        }
        if ki != 0.0 {
            for n in &nbb[i] {
                *v = axpy(*v, -dt * bvol[n.index as usize] * 2.0 * ki, n.grad_w);
            }
        }
    });
}

/// The mean of `values` over `n` particles (0 for none).
fn average(values: &[f64], n: usize) -> f64 {
    values.iter().sum::<f64>() / n.max(1) as f64
}

/// One Jacobi iteration: the stiffness values `kappa_i = residual_i alpha_i / scale` applied
/// to the velocities (`apply_kappa`); returns them.
fn jacobi_update(
    f: &mut Fluid,
    residual: &[f64],
    alpha: &[f64],
    scale: f64,
    vol: f64,
    dt: f64,
) -> Vec<f64> {
    let kappa: Vec<f64> = residual
        .par_iter()
        .zip(alpha.par_iter())
        .map(|(r, a)| r * a / scale)
        .collect();
    apply_kappa(f, &kappa, vol, dt);
    kappa
}

/// The constant-density solver: Jacobi iterations until the average predicted compression
/// is below `max_density_error` (at least 2 iterations). Returns (iterations, accumulated
/// kappa for the pressure output).
fn solve_density(f: &mut Fluid, alpha: &[f64], vol: f64, dt: f64) -> (usize, Vec<f64>) {
    let n = f.len();
    let eta = f.params.max_density_error;
    let mut total = vec![0.0; n];
    let mut it = 0;
    while it < f.params.max_iterations {
        let rate = density_rate(f, vol);
        let rho0 = f.params.rest_density;
        let err: Vec<f64> = f
            .densities
            .par_iter()
            .zip(rate.par_iter())
            .map(|(r, d)| (r / rho0 + dt * d - 1.0).max(0.0))
            .collect();
        if it >= 2 && average(&err, n) <= eta {
            break;
        }
        let kappa = jacobi_update(f, &err, alpha, dt * dt, vol, dt);
        total.iter_mut().zip(&kappa).for_each(|(t, k)| *t += k);
        it += 1;
    }
    (it, total)
}

/// The divergence-free solver: Jacobi iterations until the average compressive density
/// rate times `dt` is below `max_density_error` (at least 1 iteration; SPlisHSPlasH uses
/// the same tolerance for both solvers by default). Particles
/// with few neighbours (free surface) are left alone, as in Bender & Koschier 2017.
fn solve_divergence(f: &mut Fluid, alpha: &[f64], vol: f64, dt: f64) -> usize {
    let n = f.len();
    let eta = f.params.max_density_error / dt;
    let min_nb = if f.params.dim == 2 { 6 } else { 18 };
    let mut it = 0;
    while it < f.params.max_iterations {
        let rate = density_rate(f, vol);
        let (nbf, nbb) = (&f.fluid_neighbours, &f.boundary_neighbours);
        let rate: Vec<f64> = rate
            .par_iter()
            .enumerate()
            .map(|(i, d)| {
                if nbf[i].len() + nbb[i].len() < min_nb {
                    0.0
                } else {
                    d.max(0.0)
                }
            })
            .collect();
        if it >= 1 && average(&rate, n) <= eta {
            break;
        }
        jacobi_update(f, &rate, alpha, dt, vol, dt);
        it += 1;
    }
    it
}

/// The DFSPH solver (stateless: tolerances and iteration limits are in `SphParams`).
#[derive(Clone, Copy, Debug, Default)]
pub struct Dfsph;

impl PressureSolver for Dfsph {
    /// One DFSPH step of size `dt` (Bender & Koschier 2017 Alg. 1, in the order
    /// SPlisHSPlasH uses: neighbours, densities and factors at the current positions, the
    /// divergence solve, non-pressure forces, the density solve, then positions).
    fn step(&self, f: &mut Fluid, dt: f64) -> Result<StepStats, GridError> {
        f.find_neighbours()?;
        f.compute_densities();
        let vol = f.mass / f.params.rest_density;
        let alpha = factors(f, vol);
        let cap = f.params.max_iterations;
        let mut iterations = 0;
        let mut capped = 0;
        if f.params.divergence {
            let it = solve_divergence(f, &alpha, vol, dt);
            iterations += it;
            capped += usize::from(it >= cap);
        }
        let acc = f.non_pressure_accelerations();
        f.accelerate(&acc, dt);
        let (it, kappa) = solve_density(f, &alpha, vol, dt);
        iterations += it;
        capped += usize::from(it >= cap);
        // The pressure output is the density solver's (as in SPlisHSPlasH); see docs/sph.md.
        let rho0 = f.params.rest_density;
        f.pressures = kappa
            .par_iter()
            .zip(f.densities.par_iter())
            .map(|(k, r)| k * r * r / rho0)
            .collect();
        f.advect(dt);
        Ok(StepStats { iterations, capped })
    }
}
