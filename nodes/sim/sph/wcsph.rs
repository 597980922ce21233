//! Weakly compressible SPH as the course gives it (Becker & Teschner 2007, "Weakly
//! compressible SPH for free surface flows"; Koschier et al. 2019 Sec. 4): summation
//! density, the equation of state `p = k((rho/rho0)^gamma - 1)` clamped at 0, the symmetric
//! pressure force `a_i = -sum_j m (p_i/rho_i^2 + p_j/rho_j^2) grad W_ij`, viscosity and
//! gravity, integrated with operator splitting and symplectic Euler.

use super::fluid::{axpy, Fluid, StepStats};
use rayon::prelude::*;

/// The course's equation of state (Becker & Teschner 2007 eq. 7), clamped at 0 so the
/// free surface does not attract particles.
pub fn pressure(rho: f64, rho0: f64, k: f64, gamma: f64) -> f64 {
    (k * ((rho / rho0).powf(gamma) - 1.0)).max(0.0)
}

/// One WCSPH step of size `dt`.
pub fn step(f: &mut Fluid, dt: f64) -> Result<StepStats, String> {
    f.find_neighbours()?;
    f.compute_densities();
    let prm = &f.params;
    let (rho0, k, gamma) = (prm.rest_density, prm.stiffness, prm.exponent);
    f.p = f
        .rho
        .par_iter()
        .map(|&r| pressure(r, rho0, k, gamma))
        .collect();
    let mut acc = f.non_pressure_accelerations();
    let (m, rho, p, bvol) = (f.mass, &f.rho, &f.p, &f.bvol);
    acc.par_iter_mut()
        .zip(f.nbf.par_iter().zip(f.nbb.par_iter()))
        .enumerate()
        .for_each(|(i, (a, (nf, nb)))| {
            let pi = p[i] / (rho[i] * rho[i]);
            for n in nf {
                let j = n.j as usize;
                axpy(-m * (pi + p[j] / (rho[j] * rho[j])), n.g, a);
            }
            // Boundary particles mirror the pressure (p_b = p_i, rho_b = rho_i) and have
            // mass rho0 V_b (Akinci 2012).
            for n in nb {
                axpy(-rho0 * bvol[n.j as usize] * 2.0 * pi, n.g, a);
            }
        });
    f.v.par_iter_mut().zip(acc.par_iter()).for_each(|(v, a)| {
        axpy(dt, *a, v);
    });
    f.advect(dt);
    Ok(StepStats::default())
}
