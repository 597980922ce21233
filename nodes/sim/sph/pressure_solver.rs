//! The one interface of the SPH pressure solvers: a solver advances the fluid by one time
//! step (neighbours, densities, pressure and non-pressure forces, positions) and reports its
//! iterations. `time_step` picks the solver named by `SphParams::solver`.

use super::neighbour_grid::GridError;
use super::state::{Fluid, StepStats};

/// A pressure solver: WCSPH (`wcsph::Wcsph`) or DFSPH (`dfsph::Dfsph`).
pub trait PressureSolver {
    /// One time step of size `dt`; `Err` when the neighbour search fails.
    fn step(&self, f: &mut Fluid, dt: f64) -> Result<StepStats, GridError>;
}
