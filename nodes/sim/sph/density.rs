//! SPH density summation with boundary particles (Akinci et al. 2012 eq. 6), at the
//! positions of the last neighbour search.

use super::neighbour_grid::GridError;
use super::state::Fluid;
use rayon::prelude::*;

impl Fluid {
    /// Density by summation including the particle itself, plus the boundary particles'
    /// `rho0 V_b W_ib` (Akinci 2012 eq. 6): `rho_i = m (W(0) + sum_j W_ij) + rho0 sum_b V_b W_ib`.
    pub fn compute_densities(&mut self) {
        let m = self.mass;
        let w0 = self.kernel.w_zero();
        let rho0 = self.params.rest_density;
        let bvol = &self.boundary_volumes;
        self.densities = self
            .fluid_neighbours
            .par_iter()
            .zip(self.boundary_neighbours.par_iter())
            .map(|(f, b)| {
                let sf: f64 = f.iter().map(|n| n.w).sum();
                let sb: f64 = b.iter().map(|n| bvol[n.index as usize] * n.w).sum();
                m * (w0 + sf) + rho0 * sb
            })
            .collect();
    }

    /// Recomputes neighbours and densities at the current positions (for output).
    pub fn refresh(&mut self) -> Result<(), GridError> {
        self.find_neighbours()?;
        self.compute_densities();
        Ok(())
    }
}
