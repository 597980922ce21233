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

use super::fluid::{axpy, dot, Fluid, StepStats};
use rayon::prelude::*;

/// `alpha_i` (see the module doc); 0 for particles without neighbours.
fn factors(f: &Fluid, vol: f64) -> Vec<f64> {
    let bvol = &f.bvol;
    let tiny = 1e-6 / (f.kernel.h * f.kernel.h);
    f.nbf
        .par_iter()
        .zip(f.nbb.par_iter())
        .map(|(nf, nb)| {
            let mut gf = [0.0; 3];
            let mut gb = [0.0; 3];
            let mut sq = 0.0;
            for n in nf {
                axpy(vol, n.g, &mut gf);
                sq += dot(n.g, n.g);
            }
            for n in nb {
                axpy(bvol[n.j as usize], n.g, &mut gb);
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
    let (v, bvol) = (&f.v, &f.bvol);
    f.nbf
        .par_iter()
        .zip(f.nbb.par_iter())
        .enumerate()
        .map(|(i, (nf, nb))| {
            let mut s = 0.0;
            for n in nf {
                let j = n.j as usize;
                let vij = [v[i][0] - v[j][0], v[i][1] - v[j][1], v[i][2] - v[j][2]];
                s += vol * dot(vij, n.g);
            }
            for n in nb {
                s += bvol[n.j as usize] * dot(v[i], n.g);
            }
            s
        })
        .collect()
}

/// `v_i -= dt (sum_j V (kappa_i + kappa_j) grad W_ij + sum_b V_b 2 kappa_i grad W_ib)`.
fn apply_kappa(f: &mut Fluid, kappa: &[f64], vol: f64, dt: f64) {
    let (nbf, nbb, bvol) = (&f.nbf, &f.nbb, &f.bvol);
    f.v.par_iter_mut().enumerate().for_each(|(i, v)| {
        let ki = kappa[i];
        for n in &nbf[i] {
            axpy(-dt * vol * (ki + kappa[n.j as usize]), n.g, v);
        }
        if ki != 0.0 {
            for n in &nbb[i] {
                axpy(-dt * bvol[n.j as usize] * 2.0 * ki, n.g, v);
            }
        }
    });
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
            .rho
            .par_iter()
            .zip(rate.par_iter())
            .map(|(r, d)| (r / rho0 + dt * d - 1.0).max(0.0))
            .collect();
        let avg = err.iter().sum::<f64>() / n.max(1) as f64;
        if it >= 2 && avg <= eta {
            break;
        }
        let kappa: Vec<f64> = err
            .par_iter()
            .zip(alpha.par_iter())
            .map(|(e, a)| e * a / (dt * dt))
            .collect();
        apply_kappa(f, &kappa, vol, dt);
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
        let (nbf, nbb) = (&f.nbf, &f.nbb);
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
        let avg = rate.iter().sum::<f64>() / n.max(1) as f64;
        if it >= 1 && avg <= eta {
            break;
        }
        let kappa: Vec<f64> = rate
            .par_iter()
            .zip(alpha.par_iter())
            .map(|(d, a)| d * a / dt)
            .collect();
        apply_kappa(f, &kappa, vol, dt);
        it += 1;
    }
    it
}

/// One DFSPH step of size `dt` (Bender & Koschier 2017 Alg. 1, in the order
/// SPlisHSPlasH uses: neighbours, densities and factors at the current positions, the
/// divergence solve, non-pressure forces, the density solve, then positions).
pub fn step(f: &mut Fluid, dt: f64) -> Result<StepStats, String> {
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
    f.v.par_iter_mut().zip(acc.par_iter()).for_each(|(v, a)| {
        axpy(dt, *a, v);
    });
    let (it, kappa) = solve_density(f, &alpha, vol, dt);
    iterations += it;
    capped += usize::from(it >= cap);
    // The pressure output is the density solver's (as in SPlisHSPlasH); see docs/sph.md.
    let rho0 = f.params.rest_density;
    f.p = kappa
        .par_iter()
        .zip(f.rho.par_iter())
        .map(|(k, r)| k * r * r / rho0)
        .collect();
    f.advect(dt);
    Ok(StepStats { iterations, capped })
}
