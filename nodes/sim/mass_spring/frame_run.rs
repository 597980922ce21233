//! The stepping loop of the `mass_spring` node: the frames one execution advances, each
//! sub-step moving the control points and the keyframed sphere, then logging its energies.

use super::control::control_targets;
use super::keyframes::keyframed_center;
use super::simulator::{Method, SimError, Simulator};
use super::springs::{Energy, Sphere};
use cgnodes_api::prelude::*;

/// What the stepping loop needs beyond the simulator.
pub(super) struct Params {
    pub method: Method,
    pub h: f64,
    pub substeps: usize,
    pub sphere: Option<Sphere>,
    pub keys: Vec<(f64, [f64; 3])>,
    /// (cloth vertex, body vertex) control pairs.
    pub pairs: Vec<(usize, usize)>,
}

/// One row of the `log` table (`LOG_COLUMNS`).
pub(super) fn log_row(frame: i64, step: f64, time: f64, e: &Energy, iterations: f64) -> [f64; 8] {
    [
        frame as f64,
        step,
        time,
        e.kinetic,
        e.potential,
        e.total(),
        e.max_strain,
        iterations,
    ]
}

/// The node error for a failed step of frame `f + 1`, sub-step `s + 1`.
fn step_error(e: SimError, params: &Params, f: i64, s: usize) -> NodeError {
    match e {
        SimError::Unstable { reason, .. } => NodeError::unstable(format!(
            "{:?} integrator blew up at frame {} step {} (h = {}): {reason}; use a smaller h, more substeps, or the implicit integrator",
            params.method, f + 1, s + 1, params.h
        )),
        SimError::Solver(m) => NodeError::singular(format!("frame {} step {}: {m}", f + 1, s + 1)),
    }
}

/// The frames one execution advances: from `last` by `frames`, the body moving from
/// `control_prev` to `control_cur` across all their sub-steps.
pub(super) struct FrameRun<'a> {
    pub params: &'a Params,
    /// The frame the simulation started at (keyframe times count from it).
    pub start: i64,
    /// The frame the state is at.
    pub last: i64,
    pub frames: usize,
    pub control_prev: &'a [[f64; 3]],
    pub control_cur: &'a [[f64; 3]],
}

impl FrameRun<'_> {
    /// Steps `sim` through every sub-step of every frame, moving the control points and the
    /// keyframed sphere before each step and logging each step's energies.
    pub fn advance(
        &self,
        sim: &mut Simulator,
        log: &mut Table,
        progress: &dyn Fn(f64),
    ) -> Result<(), NodeError> {
        let params = self.params;
        let total = (self.frames * params.substeps).max(1) as f64;
        for df in 0..self.frames {
            let f = self.last + df as i64; // frame being advanced from
            for s in 0..params.substeps {
                if !params.pairs.is_empty() {
                    // The body's pose at the end of this step, between the frames' poses.
                    let k = (df * params.substeps + s + 1) as f64 / total;
                    let targets =
                        control_targets(&params.pairs, self.control_prev, self.control_cur, k);
                    sim.move_fixed(&targets)
                        .map_err(|e| NodeError::invalid("control_mesh", e.to_string()))?;
                }
                let frac = (f - self.start) as f64 + (s + 1) as f64 / params.substeps as f64;
                let sphere = params.sphere.map(|mut sp| {
                    if let Some(c) = keyframed_center(&params.keys, self.start as f64 + frac) {
                        sp.center = c;
                    }
                    sp
                });
                progress((df * params.substeps + s) as f64 / total);
                let l = sim
                    .step(sphere.as_ref())
                    .map_err(|e| step_error(e, params, f, s))?;
                log.push_row(&log_row(
                    f + 1,
                    sim.steps as f64,
                    sim.steps as f64 * params.h,
                    &l.energy,
                    l.iterations as f64,
                ));
            }
        }
        Ok(())
    }
}
