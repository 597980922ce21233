//! SPH fluids (the course's ninth assignment): the `sph_fluid` node with WCSPH and DFSPH
//! solvers, Akinci boundary particles and a uniform-grid neighbour search, and
//! `points_save` to write particles as PLY. See `docs/sph.md`.
//!
//! Layers, each depending only on those before it: the kernel, the neighbour grid and the
//! boundary sampling; the fluid's state (`state`); the neighbour lists, density summation,
//! non-pressure forces and measurements over that state; the pressure solvers behind one
//! interface (`pressure_solver`: `wcsph`, `dfsph`); time stepping (`time_step`); the nodes.

pub mod boundary;
pub mod density;
pub mod dfsph;
pub mod diagnostics;
pub mod kernel;
pub mod neighbour_grid;
pub mod neighbours;
pub mod non_pressure;
pub mod particle_box;
pub mod points_save;
pub mod pressure_solver;
pub mod sph_fluid;
pub mod state;
pub mod time_step;
pub mod wcsph;

pub use dfsph::Dfsph;
pub use neighbour_grid::GridError;
pub use pressure_solver::PressureSolver;
pub use state::{BlockError, Boundary, Fluid, Neighbour, Solver, SphParams, StepStats};
pub use time_step::{AdvanceError, StepError};
pub use wcsph::Wcsph;

use cgnodes_api::registry::Registry;

/// Registers `sph_fluid`, `points_save`, `particles_in_box` and `particles_around_box`.
pub fn register(r: &mut Registry) {
    sph_fluid::register(r);
    particle_box::register(r);
    points_save::register(r);
}
