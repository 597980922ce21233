//! Time stepping of an SPH fluid: the step size (fixed or CFL-adaptive), one step with
//! the configured pressure solver, advancing by a duration, and blow-up detection.

use super::dfsph::Dfsph;
use super::neighbour_grid::GridError;
use super::pressure_solver::PressureSolver;
use super::state::{Fluid, Solver};
use super::wcsph::Wcsph;
use cgnodes_api::types::vec3::dot;
use rayon::prelude::*;

/// Why a time step failed: the neighbour search, or the blow-up check after the step.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StepError {
    /// The particles spread too far for the neighbour grid.
    #[error(transparent)]
    Grid(#[from] GridError),
    /// A particle's state is non-finite or far faster than free fall over the box.
    #[error(
        "particle {index} has position {position:?} and velocity {velocity:?} (speed limit {limit:.1} m/s); \
         lower dt, enable the adaptive step, or raise the stiffness"
    )]
    Runaway {
        /// The first offending particle found.
        index: usize,
        /// Its position.
        position: [f64; 3],
        /// Its velocity.
        velocity: [f64; 3],
        /// The speed limit (m/s).
        limit: f64,
    },
    /// The fluid is compressed to five times its rest density (or a density is NaN).
    #[error(
        "the density reached {max:.1} (rest density {rest}); the fluid is collapsing: \
         raise the stiffness or lower dt"
    )]
    Collapsing {
        /// The largest density.
        max: f64,
        /// The rest density.
        rest: f64,
    },
}

/// A failed step within `Fluid::advance`, naming the step.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("step {step} (t = {time:.4} s, dt = {dt:.2e}): {cause}")]
pub struct AdvanceError {
    /// Steps taken when the error was found.
    pub step: usize,
    /// Simulated time then.
    pub time: f64,
    /// The step size tried.
    pub dt: f64,
    /// What went wrong.
    #[source]
    pub cause: StepError,
}

/// The pressure solver named by `kind`.
pub fn pressure_solver(kind: Solver) -> &'static dyn PressureSolver {
    match kind {
        Solver::Wcsph => &Wcsph,
        Solver::Dfsph => &Dfsph,
    }
}

impl Fluid {
    /// The next step size: `dt`, or with `cfl > 0` the CFL bound `cfl * 2r / v_max`, the
    /// explicit viscosity bound, and for WCSPH also `cfl * h / c` with the EOS sound speed
    /// `c = sqrt(k gamma / rho0)`.
    pub fn step_size(&self) -> f64 {
        let p = &self.params;
        if p.cfl <= 0.0 {
            return p.dt;
        }
        let mut dt = p.dt;
        let vmax = self.max_speed() + (p.gravity.abs() * p.dt);
        if vmax > 0.0 {
            dt = dt.min(p.cfl * 2.0 * p.particle_radius / vmax);
        }
        if p.viscosity > 0.0 {
            // Explicit viscosity: dt <= 0.125 l^2 / nu with the smoothing length l = h/2
            // (Monaghan 1992).
            let l = 0.5 * self.kernel.h;
            dt = dt.min(0.125 * l * l / p.viscosity);
        }
        if p.solver == Solver::Wcsph && p.stiffness > 0.0 {
            let c = (p.stiffness * p.exponent / p.rest_density).sqrt();
            dt = dt.min(p.cfl * self.kernel.h / c);
        }
        dt.max(p.dt * 1e-4)
    }

    /// One time step of size `dt` with the configured solver.
    pub fn step(&mut self, dt: f64) -> Result<(), StepError> {
        self.last = pressure_solver(self.params.solver).step(self, dt)?;
        self.time += dt;
        self.steps += 1;
        self.total_iterations += self.last.iterations;
        self.capped_solves += self.last.capped;
        self.check()
    }

    /// Advances by `duration` in steps of `step_size()`; `Err` names the step that blew up.
    pub fn advance(&mut self, duration: f64) -> Result<usize, AdvanceError> {
        self.advance_progress(duration, &|_| {})
    }

    /// `advance`, reporting the fraction of `duration` simulated after each step.
    pub fn advance_progress(
        &mut self,
        duration: f64,
        progress: &dyn Fn(f64),
    ) -> Result<usize, AdvanceError> {
        let mut left = duration;
        let mut n = 0;
        while left > 1e-12 * duration.max(1e-12) {
            progress(1.0 - left / duration);
            let mut dt = self.step_size().min(left);
            // Avoid a sliver of a last step.
            if left - dt < 0.2 * dt {
                dt = if left <= dt { left } else { 0.5 * left };
            }
            self.step(dt).map_err(|cause| AdvanceError {
                step: self.steps,
                time: self.time,
                dt,
                cause,
            })?;
            left -= dt;
            n += 1;
        }
        Ok(n)
    }

    /// Blow-up detection: non-finite state, a speed far beyond free fall over the box, or
    /// a fluid compressed to five times its rest density (particles piling up; the course's
    /// stiffness 500 legitimately reaches 1.6x at the bottom of a 1.25 m column at rest).
    fn check(&self) -> Result<(), StepError> {
        let p = &self.params;
        let mut diag = 0.0;
        for a in 0..p.dim {
            diag += (p.box_max[a] - p.box_min[a]).powi(2);
        }
        let vlim = 50.0 * (2.0 * p.gravity.abs().max(1.0) * diag.sqrt()).sqrt();
        let bad = self
            .positions
            .par_iter()
            .zip(self.velocities.par_iter())
            .position_any(|(x, v)| {
                !(x.iter().all(|c| c.is_finite()) && v.iter().all(|c| c.is_finite()))
                    || dot(*v, *v) > vlim * vlim
            });
        if let Some(i) = bad {
            return Err(StepError::Runaway {
                index: i,
                position: self.positions[i],
                velocity: self.velocities[i],
                limit: vlim,
            });
        }
        let rmax = self.densities.iter().cloned().fold(0.0, f64::max);
        if rmax.is_nan() || rmax >= 5.0 * p.rest_density {
            return Err(StepError::Collapsing {
                max: rmax,
                rest: p.rest_density,
            });
        }
        Ok(())
    }
}
