//! The non-pressure accelerations every SPH solver applies: gravity and the course's
//! viscosity (an SPH Laplacian of the velocity).

use super::state::Fluid;
use cgnodes_api::types::vec3::{axpy, dot, sub};
use rayon::prelude::*;

impl Fluid {
    /// Gravity plus the course's viscosity, the SPH Laplacian of Koschier et al. 2019
    /// eq. (32): `a_i = 2(d+2) nu sum_j (m/rho_ij) (v_ij . x_ij) / (|x_ij|^2 + 0.01 h^2) grad W_ij`,
    /// with `rho_ij = (rho_i + rho_j)/2` so that the pair forces are equal and opposite.
    pub fn non_pressure_accelerations(&self) -> Vec<[f64; 3]> {
        let d = self.params.dim as f64;
        let nu = self.params.viscosity;
        let m = self.mass;
        let h2 = self.kernel.h * self.kernel.h;
        let mut g = [0.0; 3];
        g[self.up()] = self.params.gravity;
        let (x, v, rho) = (&self.positions, &self.velocities, &self.densities);
        self.fluid_neighbours
            .par_iter()
            .enumerate()
            .map(|(i, nb)| {
                let mut a = g;
                if nu > 0.0 {
                    let c = 2.0 * (d + 2.0) * nu * m;
                    for n in nb {
                        let j = n.index as usize;
                        let xij = sub(x[i], x[j]);
                        let vij = sub(v[i], v[j]);
                        let s = c * dot(vij, xij)
                            / (0.5 * (rho[i] + rho[j]) * (dot(xij, xij) + 0.01 * h2));
                        a = axpy(a, s, n.grad_w);
                    }
                }
                a
            })
            .collect()
    }
}
