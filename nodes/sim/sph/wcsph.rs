//! Weakly compressible SPH as the course gives it (Becker & Teschner 2007, "Weakly
//! compressible SPH for free surface flows"; Koschier et al. 2019 Sec. 4): summation
//! density, the equation of state `p = k((rho/rho0)^gamma - 1)` clamped at 0, the symmetric
//! pressure force `a_i = -sum_j m (p_i/rho_i^2 + p_j/rho_j^2) grad W_ij`, viscosity and
//! gravity, integrated with operator splitting and symplectic Euler.

use super::neighbour_grid::GridError;
use super::pressure_solver::PressureSolver;
use super::state::{Fluid, StepStats};
use cgnodes_api::types::vec3::axpy;
use rayon::prelude::*;

/// The course's equation of state (Becker & Teschner 2007 eq. 7), clamped at 0 so the
/// free surface does not attract particles.
pub fn pressure(rho: f64, rho0: f64, k: f64, gamma: f64) -> f64 {
    (k * ((rho / rho0).powf(gamma) - 1.0)).max(0.0)
}

/// The WCSPH solver (stateless: the stiffness and exponent are in `SphParams`).
#[derive(Clone, Copy, Debug, Default)]
pub struct Wcsph;

impl PressureSolver for Wcsph {
    /// One WCSPH step of size `dt`.
    fn step(&self, f: &mut Fluid, dt: f64) -> Result<StepStats, GridError> {
        f.find_neighbours()?;
        f.compute_densities();
        let prm = &f.params;
        let (rho0, k, gamma) = (prm.rest_density, prm.stiffness, prm.exponent);
        f.pressures = f
            .densities
            .par_iter()
            .map(|&r| pressure(r, rho0, k, gamma))
            .collect();
        let mut acc = f.non_pressure_accelerations();
        let (m, rho, p, bvol) = (f.mass, &f.densities, &f.pressures, &f.boundary_volumes);
        acc.par_iter_mut()
            .zip(
                f.fluid_neighbours
                    .par_iter()
                    .zip(f.boundary_neighbours.par_iter()),
            )
            .enumerate()
            .for_each(|(i, (a, (nf, nb)))| {
                let pi = p[i] / (rho[i] * rho[i]);
                for n in nf {
                    let j = n.index as usize;
                    *a = axpy(*a, -m * (pi + p[j] / (rho[j] * rho[j])), n.grad_w);
                }
                // Boundary particles mirror the pressure (p_b = p_i, rho_b = rho_i) and have
                // mass rho0 V_b (Akinci 2012).
                for n in nb {
                    *a = axpy(*a, -rho0 * bvol[n.index as usize] * 2.0 * pi, n.grad_w);
                }
            });
        f.accelerate(&acc, dt);
        f.advect(dt);
        Ok(StepStats::default())
    }
}
