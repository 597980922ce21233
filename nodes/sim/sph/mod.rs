//! SPH fluids (the course's ninth assignment): the `sph_fluid` node with WCSPH and DFSPH
//! solvers, Akinci boundary particles and a uniform-grid neighbour search, and
//! `points_save` to write particles as PLY. See `docs/sph.md`.

pub mod boundary;
pub mod dam_break;
pub mod dfsph;
pub mod fluid;
pub mod grid;
pub mod kernel;
pub mod points_save;
pub mod sph_fluid;
pub mod wcsph;

pub use fluid::{Boundary, Fluid, Solver, SphParams};

use crate::registry::Registry;

/// Registers `sph_fluid` and `points_save`.
pub fn register(r: &mut Registry) {
    sph_fluid::register(r);
    points_save::register(r);
}
