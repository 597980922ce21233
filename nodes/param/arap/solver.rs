//! The state of one `arap_parameterize` run and its steps: the global step (a preconditioned
//! gradient step), the fold-free search (local re-solves, then refactorizations, until the
//! step is no longer blocked), Armijo's backtracking, and the bookkeeping of an accepted
//! step. `iterate` is the loop over them.

use super::energy::{evaluate, ArapIteration, ArapResult};
use super::error::ArapError;
use super::fold_free::FoldFree;
use super::frames::{Similarity, PAR_CHUNK};
use super::injective::orientation_and_flips;
use super::line_search::{area_floors, Directional, StepLimits};
use super::options::{
    ArapOptions, ARMIJO_C, BLOCKED_STEP, LOCAL_GIVE_UP, LOCAL_ROUNDS, MAX_BACKTRACKS, MIN_STEP,
    STEP_SAFETY,
};
use super::prepared::ArapSystem;
use super::system::{descent_direction, gradient_into};
use super::StopReason;
use faer::{Mat, Par};
use rayon::prelude::*;
use std::time::Instant;

/// `arap_parameterize` on a rayon pool thread: the local/global loop.
pub(super) fn iterate(
    system: ArapSystem,
    init_uv: &[[f64; 2]],
    opts: &ArapOptions,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<ArapResult, ArapError> {
    let mut s = Solver::new(system, init_uv, opts)?;
    while s.it < opts.iterations {
        progress(s.it as f64 / opts.iterations as f64);
        if s.sys.factor.is_none() {
            s.stop = StopReason::Tolerance;
            break;
        }
        s.it += 1;
        s.global_step();
        let search = if opts.injective {
            match s.fold_free_search()? {
                Some(search) => search,
                None => break,
            }
        } else {
            Search::FULL
        };
        let Some(accepted) = s.backtrack(&search) else {
            break;
        };
        if s.accept(&search, accepted) {
            break;
        }
    }
    Ok(s.finish())
}

/// Where the backtracking starts along the search direction `d`.
struct Search {
    /// First step length tried.
    step: f64,
    /// Derivative of the energy (per unit area) along `d` at step 0 (negative; 0 when the
    /// line search only checks for a decrease).
    slope: f64,
    /// Whether the step was cut short to keep every triangle's orientation.
    blocked: bool,
    /// Numeric refactorizations during this iteration.
    refactors: usize,
}

impl Search {
    /// The plain local/global step: the whole global step, no slope test.
    const FULL: Search = Search {
        step: 1.0,
        slope: 0.0,
        blocked: false,
        refactors: 0,
    };
}

/// A step that passed Armijo's test.
struct Accepted {
    step: f64,
    energy: f64,
    flips: usize,
}

/// Everything one run keeps between its steps.
struct Solver<'a> {
    opts: &'a ArapOptions,
    /// When the call started (the log's `elapsed_ms`).
    start: Instant,
    /// The frames, the factored Laplacian and its numbering (built before the start is read).
    sys: ArapSystem,
    lambda: Option<f64>,
    total_area: f64,
    /// `-1` when the start is clockwise: the run works on the mirrored UVs.
    orient: f64,

    /// Scratch of the solves.
    rhs: Mat<f64>,
    /// `∇E` on the free vertices, in elimination order.
    gradient: Mat<f64>,
    /// Scratch of `gradient_into`, one buffer per half of the triangles.
    gradient_halves: [Vec<[f64; 2]>; 2],
    /// The search direction, per vertex.
    d: Vec<[f64; 2]>,

    /// The current UVs (mirrored when `orient < 0`) and their local step's targets.
    uv: Vec<[f64; 2]>,
    targets: Vec<Similarity>,
    /// The UVs and targets of the step being tried.
    trial: Vec<[f64; 2]>,
    trial_targets: Vec<Similarity>,
    /// The energy at `uv`, per unit area.
    energy: f64,
    /// The fold-free line search's per-triangle state.
    step_limits: StepLimits,
    /// The fold-free mode's weights, counters and scratch.
    fold: FoldFree,

    /// Iterations started.
    it: usize,
    log: Vec<ArapIteration>,
    stop: StopReason,
    /// Details of a `NoProgress` stop.
    detail: String,
}

impl<'a> Solver<'a> {
    /// Checks the start and the options against `system` and evaluates the start (log row 0).
    fn new(
        system: ArapSystem,
        init_uv: &[[f64; 2]],
        opts: &'a ArapOptions,
    ) -> Result<Solver<'a>, ArapError> {
        let start = Instant::now();
        if !system.fits(opts) {
            return Err(ArapError::SystemOptions);
        }
        let (n, frames) = (system.n, &system.frames);
        validate(n, init_uv, opts)?;
        let m = frames.len();
        let lambda = opts.lambda;

        // Orientation of the start; work counter-clockwise, mirroring a clockwise start.
        let (orient, flips0) = orientation_and_flips(frames, init_uv);
        if opts.injective && flips0 > 0 {
            return Err(ArapError::FoldedStart(flips0));
        }
        let uv: Vec<[f64; 2]> = init_uv.iter().map(|p| [p[0], orient * p[1]]).collect();
        let nf = system.row_vertex.len();
        let fold = FoldFree::new(n, frames, opts);
        // per triangle, twice the UV area of the margin and of the hard floor (see AREA_MARGIN)
        let floor2 = if opts.injective {
            area_floors(frames, &uv)
        } else {
            Vec::new()
        };

        let total_area = frames.total_area;
        let mut targets: Vec<Similarity> = vec![[1.0, 0.0]; m];
        let trial_targets: Vec<Similarity> = vec![[1.0, 0.0]; m];
        let (e_sum, flips) = evaluate(frames, &uv, lambda, &mut targets);
        let energy = e_sum / total_area;
        let log = vec![ArapIteration {
            iteration: 0,
            energy,
            flips,
            elapsed_ms: ms(start),
            step: 0.0,
            blocked: false,
            refactors: 0,
        }];
        Ok(Solver {
            opts,
            start,
            lambda,
            total_area,
            orient,
            sys: system,
            rhs: Mat::<f64>::zeros(nf, 2),
            gradient: Mat::<f64>::zeros(nf, 2),
            gradient_halves: [Vec::new(), Vec::new()],
            d: vec![[0.0; 2]; n],
            trial: uv.clone(),
            uv,
            targets,
            trial_targets,
            energy,
            step_limits: StepLimits::new(floor2),
            fold,
            it: 0,
            log,
            stop: StopReason::Iterations,
            detail: String::new(),
        })
    }

    /// Global step, written as a preconditioned gradient step: d = -Δ_W⁻¹ ∇E. With unit
    /// weights this is exactly Liu et al.'s global solve minus the current UVs;
    /// ∇E at vertex i is Σ_t Σ_j cot θ_ij ((u_i - u_j) - L_t (x_i - x_j)) (eq. 6).
    fn global_step(&mut self) {
        gradient_into(
            &self.sys.frames,
            &self.sys.corner_w,
            &self.targets,
            &self.uv,
            &self.sys.row_of,
            &mut self.gradient_halves,
            &mut self.gradient,
        );
        self.solve_direction();
    }

    /// `d` from the current gradient and factor.
    fn solve_direction(&mut self) {
        let factor = self
            .sys
            .factor
            .as_ref()
            .expect("the loop stops without free vertices");
        descent_direction(
            factor,
            &self.gradient,
            &mut self.rhs,
            &self.sys.row_vertex,
            &mut self.d,
        );
    }

    /// The line search's pass over the triangles along `d` (only over `touched` when given).
    fn directional(&mut self, changed: Option<&[u32]>) -> Directional {
        self.step_limits
            .directional(&self.sys.frames, &self.uv, &self.d, &self.targets, changed)
    }

    /// Fold-free mode: shapes `d` until the orientation-preserving step is no longer blocked
    /// (or the schedule allows no more), and returns where the backtracking starts; `None`
    /// when the run stalls (`stop` and `detail` set).
    fn fold_free_search(&mut self) -> Result<Option<Search>, ArapError> {
        let mut dir = self.directional(None);
        // A blocked step is first reshaped locally: the blocking triangles are stiffened
        // and the rings around them re-solved with the stiffened weights, the rest of
        // the global step kept (`local_resolve`); refactoring the whole Laplacian (below)
        // is left for what that does not unblock.
        if self.opts.local_rings > 0 {
            dir = self.local_rounds(dir);
        }
        let (dir, iter_refactors) = self.refactor_blocked(dir)?;
        self.fold.refactors += iter_refactors;
        let slope = dir.slope / self.total_area; // per unit area, like `energy`
        let step = dir.best_step.min(STEP_SAFETY * dir.max_step);
        let blocked = STEP_SAFETY * dir.max_step < dir.best_step;
        let it = self.it;
        if dir.max_step < MIN_STEP {
            self.stop = StopReason::NoProgress;
            self.detail = format!(
                "orientation-preserving step {:.3e} at iteration {it}",
                dir.max_step
            );
            return Ok(None);
        }
        if slope.is_nan() || slope >= 0.0 {
            // zero: already stationary for these targets; positive/NaN: no descent left
            self.stop = if slope == 0.0 {
                StopReason::Tolerance
            } else {
                StopReason::NoProgress
            };
            self.detail = format!("slope {slope:.3e} along the search direction at iteration {it}");
            return Ok(None);
        }
        Ok(Some(Search {
            step,
            slope,
            blocked,
            refactors: iter_refactors,
        }))
    }

    /// Up to `LOCAL_ROUNDS` local stiffened re-solves of a blocked step; back to the global
    /// direction if they lose the descent.
    fn local_rounds(&mut self, mut dir: Directional) -> Directional {
        let mut local = false;
        for _ in 0..LOCAL_ROUNDS {
            if STEP_SAFETY * dir.max_step >= BLOCKED_STEP * dir.best_step {
                break;
            }
            let before = dir.max_step / dir.best_step;
            self.fold.stiffen(&self.step_limits.limits, dir.best_step);
            let solved = self.fold.local_resolve(
                &self.sys.frames,
                &self.step_limits.limits,
                dir.best_step,
                &self.sys.row_of,
                &self.gradient,
                &mut self.d,
            );
            if solved.is_err() {
                break;
            }
            dir = self.step_limits.directional(
                &self.sys.frames,
                &self.uv,
                &self.d,
                &self.targets,
                Some(&self.fold.scratch.touched),
            );
            local = true;
            self.fold.local_solves += 1;
            if dir.max_step / dir.best_step < LOCAL_GIVE_UP * before {
                break;
            }
        }
        if local && (dir.slope.is_nan() || dir.slope >= 0.0) {
            // the local re-solve lost the descent: back to the global direction
            self.solve_direction();
            dir = self.directional(None);
        }
        dir
    }

    /// While the step is blocked: stiffen the triangles that the step would flip (weights
    /// accumulate; the factor is refreshed on the schedule's triggers only). Returns the
    /// final pass and the number of refactorizations.
    fn refactor_blocked(
        &mut self,
        mut dir: Directional,
    ) -> Result<(Directional, usize), ArapError> {
        let sched = self.opts.refactor;
        let m = self.sys.frames.len();
        let mut iter_refactors = 0;
        loop {
            if STEP_SAFETY * dir.max_step >= BLOCKED_STEP * dir.best_step {
                self.fold.blocked_run = 0;
                break;
            }
            if iter_refactors == 0 {
                self.fold.blocked_run += 1;
            }
            self.fold.stiffen(&self.step_limits.limits, dir.best_step);
            let due = self.fold.refactor_due(&sched, m, &dir);
            if self.fold.pending == 0 || !due || iter_refactors >= sched.per_iteration {
                break;
            }
            let factor = self
                .sys
                .factor
                .as_mut()
                .expect("the loop stops without free vertices");
            let (trip, trip_tri, weights) =
                (&self.sys.trip, &self.sys.trip_tri, &self.fold.weights);
            factor
                .refactor_with(
                    trip.len(),
                    |k| trip[k].val * weights[trip_tri[k] as usize],
                    Par::Seq,
                )
                .map_err(ArapError::SingularLaplacian)?;
            (self.fold.pending, self.fold.blocked_run) = (0, 0);
            iter_refactors += 1;
            self.solve_direction();
            dir = self.directional(None);
        }
        Ok((dir, iter_refactors))
    }

    /// Armijo's backtracking from `search.step` along `d`; `None` when no step is accepted
    /// (`stop` and `detail` set). The trial UVs and targets are left in `trial`.
    fn backtrack(&mut self, search: &Search) -> Option<Accepted> {
        let slope = search.slope;
        let mut step = search.step;
        let mut accepted = None;
        let first_step = step;
        for _ in 0..MAX_BACKTRACKS {
            if step <= 0.0 || !step.is_finite() {
                break;
            }
            self.trial
                .par_iter_mut()
                .zip(self.uv.par_iter().zip(self.d.par_iter()))
                .with_min_len(PAR_CHUNK)
                .for_each(|(o, (u, dv))| *o = [u[0] + step * dv[0], u[1] + step * dv[1]]);
            let (e_sum, fl) = evaluate(
                &self.sys.frames,
                &self.trial,
                self.lambda,
                &mut self.trial_targets,
            );
            let e = e_sum / self.total_area;
            let ok_orient = !self.opts.injective || fl == 0;
            if ok_orient && e.is_finite() && e <= self.energy + ARMIJO_C * step * slope {
                accepted = Some((e, fl));
                break;
            }
            step *= 0.5;
        }
        let Some((energy, flips)) = accepted else {
            self.stop = StopReason::NoProgress;
            self.detail = format!(
                "line search failed at iteration {} (slope {slope:.3e}, first step {first_step:.3e})",
                self.it
            );
            return None;
        };
        Some(Accepted {
            step,
            energy,
            flips,
        })
    }

    /// Moves to the trial UVs and logs the iteration; true when the run has converged
    /// (`stop` set).
    fn accept(&mut self, search: &Search, accepted: Accepted) -> bool {
        std::mem::swap(&mut self.uv, &mut self.trial);
        std::mem::swap(&mut self.targets, &mut self.trial_targets);
        let e_old = self.energy;
        self.energy = accepted.energy;
        self.log.push(ArapIteration {
            iteration: self.it,
            energy: self.energy,
            flips: accepted.flips,
            elapsed_ms: ms(self.start),
            step: accepted.step,
            blocked: search.blocked,
            refactors: search.refactors,
        });
        if e_old - self.energy <= self.opts.tolerance * e_old {
            // a step cut short by a triangle about to flip is a stall, not convergence
            self.stop = if search.blocked {
                StopReason::NoProgress
            } else {
                StopReason::Tolerance
            };
            return true;
        }
        false
    }

    /// The result, mirrored back if the start was clockwise.
    fn finish(self) -> ArapResult {
        let mut uv = self.uv;
        if self.orient < 0.0 {
            for p in &mut uv {
                p[1] = -p[1];
            }
        }
        let flips = self.log.last().map_or(0, |r| r.flips);
        ArapResult {
            uv,
            log: self.log,
            stop_reason: self.stop,
            flips,
            energy: self.energy,
            reweighted: self.fold.reweighted,
            refactors: self.fold.refactors,
            local_solves: self.fold.local_solves,
            stop_detail: self.detail,
        }
    }
}

/// The checks of the start and of the options `ArapSystem::new` does not use, in the order
/// they are reported.
fn validate(n: usize, init_uv: &[[f64; 2]], opts: &ArapOptions) -> Result<(), ArapError> {
    if init_uv.len() != n {
        return Err(ArapError::InitLength {
            len: init_uv.len(),
            vertices: n,
        });
    }
    if let Some(v) = init_uv
        .iter()
        .position(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return Err(ArapError::InitNotFinite(v));
    }
    if !(opts.tolerance >= 0.0 && opts.tolerance.is_finite()) {
        return Err(ArapError::Tolerance);
    }
    if let Some(l) = opts.lambda {
        if !(l >= 0.0 && l.is_finite()) {
            return Err(ArapError::Lambda);
        }
    }
    Ok(())
}

fn ms(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}
