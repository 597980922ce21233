//! The per-step neighbour lists of the fluid particles: for each particle, its fluid and
//! boundary neighbours within the support radius with the kernel value and gradient, found
//! through uniform grids (`neighbour_grid`) and computed once per step so that every
//! solver iteration reuses them.

use super::kernel::CubicSpline;
use super::neighbour_grid::{GridError, NeighbourGrid};
use super::state::{Fluid, Neighbour};
use cgnodes_api::types::vec3::{dot, sub};
use rayon::prelude::*;

/// `j` as a neighbour of a particle at `xi` when `x_j` lies within the support radius.
#[inline]
fn neighbour(kern: &CubicSpline, xi: [f64; 3], xj: [f64; 3], j: usize) -> Option<Neighbour> {
    let h = kern.h;
    let d = sub(xi, xj);
    let r2 = dot(d, d);
    (r2 < h * h).then(|| Neighbour {
        index: j as u32,
        w: kern.w(r2.sqrt()),
        grad_w: kern.grad(d),
    })
}

impl Fluid {
    /// Rebuilds the neighbour lists (uniform grid, cell = support radius) with the kernel
    /// values and gradients at the current positions.
    pub fn find_neighbours(&mut self) -> Result<(), GridError> {
        let h = self.kernel.h;
        let grid = NeighbourGrid::build(&self.positions, h)?;
        let kern = self.kernel;
        let x = &self.positions;
        let bx = &self.boundary_positions;
        let bgrid = &self.boundary_grid;
        let lists: Vec<(Vec<Neighbour>, Vec<Neighbour>)> = (0..x.len())
            .into_par_iter()
            .map(|i| {
                let xi = x[i];
                let mut f = Vec::with_capacity(48);
                grid.for_each_candidate(&xi, |j| {
                    if j == i {
                        return;
                    }
                    f.extend(neighbour(&kern, xi, x[j], j));
                });
                let mut b = Vec::new();
                bgrid.for_each_candidate(&xi, |j| {
                    b.extend(neighbour(&kern, xi, bx[j], j));
                });
                (f, b)
            })
            .collect();
        let (f, b): (Vec<_>, Vec<_>) = lists.into_iter().unzip();
        self.fluid_neighbours = f;
        self.boundary_neighbours = b;
        Ok(())
    }
}
