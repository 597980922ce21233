//! The mass-spring time stepper: a `Model` and its `State` advanced step by step with one of
//! four integrators (`semi_implicit`, `implicit`, `quasi_newton`, `projective`), and blow-up detection (NaN,
//! infinity or runaway energy against the model's energy scale). Plain data in, plain data
//! out: the `mass_spring` node and the tests and benchmarks drive it directly.

use super::implicit::{Implicit, NewtonError, NewtonOptions, NewtonProfile};
use super::projective::Projective;
use super::quasi_newton::{QuasiNewton, QuasiNewtonOptions};
use super::semi_implicit::SemiImplicit;
pub use super::springs::SetupError;
use super::springs::{self, energy, Energy, Model, Sphere, State};

/// Which time integrator advances the system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Symplectic Euler.
    SemiImplicit,
    /// Backward Euler by Newton's method.
    Implicit,
    /// Backward Euler by L-BFGS with the projective matrix as initial Hessian (Liu et al. 2017).
    QuasiNewton,
    /// Liu et al. 2013 local/global.
    Projective,
}

/// Solver settings beyond the model.
#[derive(Clone, Copy, Debug)]
pub struct SolverOptions {
    /// Newton options (implicit).
    pub newton: NewtonOptions,
    /// L-BFGS options (quasi_newton).
    pub quasi_newton: QuasiNewtonOptions,
    /// Local/global iterations per step (projective).
    pub pd_iterations: usize,
    /// A step is reported unstable when the total energy exceeds its initial value by more
    /// than this factor times the model's energy scale (see `energy_scale`).
    pub blowup_factor: f64,
}

impl Default for SolverOptions {
    fn default() -> Self {
        SolverOptions {
            newton: NewtonOptions::default(),
            quasi_newton: QuasiNewtonOptions::default(),
            pd_iterations: 10,
            blowup_factor: 100.0,
        }
    }
}

enum Solver {
    Semi(SemiImplicit),
    Implicit(Box<Implicit>),
    QuasiNewton(Box<QuasiNewton>),
    Projective(Box<Projective>),
}

/// What one step did.
#[derive(Clone, Copy, Debug, Default)]
pub struct StepLog {
    /// Energies after the step.
    pub energy: Energy,
    /// Newton iterations (implicit), local/global iterations (projective), 0 otherwise.
    pub iterations: usize,
}

/// Why `Simulator::move_fixed` refused a target.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MoveError {
    /// The vertex is out of range or not fixed.
    #[error("vertex {0} is not a fixed vertex of the model")]
    NotFixed(usize),
    /// The vertex's target has a NaN or infinite coordinate.
    #[error("target of vertex {0} is not finite")]
    NonFiniteTarget(usize),
}

/// Why a step failed.
#[derive(Clone, Debug, PartialEq)]
pub enum SimError {
    /// NaN, infinity or runaway energy at step `step` (0-based count of steps taken).
    Unstable {
        /// The step that blew up.
        step: usize,
        /// What was seen.
        reason: String,
    },
    /// A linear solve failed.
    Solver(String),
}

/// The energy a healthy run stays within: `M |g| D + sum_s 1/2 k_s (0.1 L_s)^2` (falling by the
/// model's size `D`, stretching every spring by 10 %), plus the initial kinetic energy.
pub fn energy_scale(m: &Model, x: &[[f64; 3]], e0: &Energy) -> f64 {
    let (lo, hi) = bounds(x);
    let diag = springs::norm(springs::sub(hi, lo));
    let mass: f64 = m.mass.iter().sum();
    let g = springs::norm(m.gravity);
    let spring: f64 = (0..m.springs.len())
        .map(|s| 0.5 * m.springs.k[s] * (0.1 * m.springs.rest[s]).powi(2))
        .sum();
    mass * g * diag + spring + e0.kinetic.abs() + e0.potential.abs()
}

fn bounds(x: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in x {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    if x.is_empty() {
        ([0.0; 3], [0.0; 3])
    } else {
        (lo, hi)
    }
}

/// Advances a `Model` step by step with one integrator and watches for blow-ups.
pub struct Simulator {
    /// The dynamics.
    pub model: Model,
    /// Current positions and velocities.
    pub state: State,
    /// Positions gravity's potential energy is measured from.
    pub x_ref: Vec<[f64; 3]>,
    /// Time step.
    pub h: f64,
    /// Steps taken.
    pub steps: usize,
    /// The integrator.
    pub method: Method,
    solver: Solver,
    e0: f64,
    e_limit: f64,
}

impl Simulator {
    /// A simulator starting at `x0` with velocities `v0` (zero when `None`).
    pub fn new(
        model: Model,
        x0: Vec<[f64; 3]>,
        v0: Option<Vec<[f64; 3]>>,
        method: Method,
        h: f64,
        opts: SolverOptions,
    ) -> Result<Simulator, SetupError> {
        model.check()?;
        let n = model.num_vertices();
        if x0.len() != n {
            return Err(SetupError::Invalid(format!(
                "{} positions for {n} vertices",
                x0.len()
            )));
        }
        if !(h.is_finite() && h > 0.0) {
            return Err(SetupError::Invalid(format!(
                "time step {h} must be positive"
            )));
        }
        let v = v0.unwrap_or_else(|| vec![[0.0; 3]; n]);
        if v.len() != n {
            return Err(SetupError::Invalid(format!(
                "{} velocities for {n} vertices",
                v.len()
            )));
        }
        let solver = match method {
            Method::SemiImplicit => Solver::Semi(SemiImplicit::new(&model)),
            Method::Implicit => Solver::Implicit(Box::new(Implicit::new(&model, opts.newton))),
            Method::QuasiNewton => {
                Solver::QuasiNewton(Box::new(QuasiNewton::new(&model, h, opts.quasi_newton)?))
            }
            Method::Projective => {
                Solver::Projective(Box::new(Projective::new(&model, h, opts.pd_iterations)?))
            }
        };
        let state = State { x: x0.clone(), v };
        let e = energy(&model, &state, &x0, None);
        let scale = energy_scale(&model, &x0, &e);
        Ok(Simulator {
            e0: e.total(),
            e_limit: opts.blowup_factor * scale,
            model,
            state,
            x_ref: x0,
            h,
            steps: 0,
            method,
            solver,
        })
    }

    /// Moves fixed vertices to new positions (control points following a body) before the
    /// next step; their velocity stays zero, as the integrators keep it for fixed vertices.
    /// `Err` names a vertex that is out of range or not fixed.
    pub fn move_fixed(&mut self, targets: &[(usize, [f64; 3])]) -> Result<(), MoveError> {
        for &(i, p) in targets {
            if !self.model.fixed.get(i).copied().unwrap_or(false) {
                return Err(MoveError::NotFixed(i));
            }
            if p.iter().any(|c| !c.is_finite()) {
                return Err(MoveError::NonFiniteTarget(i));
            }
            self.state.x[i] = p;
            self.state.v[i] = [0.0; 3];
        }
        Ok(())
    }

    /// Energy of the current state.
    pub fn energy(&self, sphere: Option<&Sphere>) -> Energy {
        energy(&self.model, &self.state, &self.x_ref, sphere)
    }

    /// Number of symbolic and numeric factorizations so far (implicit only).
    pub fn factorizations(&self) -> Option<(usize, usize)> {
        match &self.solver {
            Solver::Implicit(s) => Some((s.symbolic_count, s.numeric_count)),
            _ => None,
        }
    }

    /// Where the implicit solver's time went, per phase (implicit only).
    pub fn newton_profile(&self) -> Option<NewtonProfile> {
        match &self.solver {
            Solver::Implicit(s) => Some(s.profile),
            _ => None,
        }
    }

    /// One step of length `h` with the collider at `sphere` (its position at the step's end),
    /// then the energy check: fails with `Unstable` on NaN, infinity or runaway energy.
    pub fn step(&mut self, sphere: Option<&Sphere>) -> Result<StepLog, SimError> {
        let iterations = self.advance(sphere)?;
        let energy = self.check_energy(sphere)?;
        Ok(StepLog { energy, iterations })
    }

    /// One step without the energy check (only NaN and infinity are caught); returns the
    /// iterations. For callers that check energy less often (`check_energy`), e.g. once per
    /// frame in benchmarks.
    pub fn advance(&mut self, sphere: Option<&Sphere>) -> Result<usize, SimError> {
        let h = self.h;
        let step = self.steps;
        let iterations = match &mut self.solver {
            Solver::Semi(s) => {
                s.step(&self.model, &mut self.state, h, sphere);
                0
            }
            Solver::Implicit(s) => {
                s.step(&self.model, &mut self.state, h, sphere)
                    .map_err(|e| match e {
                        NewtonError::NonFiniteGradient | NewtonError::NonFiniteStep => {
                            SimError::Unstable {
                                step,
                                reason: e.to_string(),
                            }
                        }
                        NewtonError::NotPositiveDefinite(_) => SimError::Solver(e.to_string()),
                    })?
            }
            Solver::QuasiNewton(s) => {
                s.step(&self.model, &mut self.state, sphere)
                    .map_err(|e| SimError::Unstable {
                        step,
                        reason: e.to_string(),
                    })?
            }
            Solver::Projective(s) => s.step(&self.model, &mut self.state, sphere),
        };
        self.steps += 1;
        if let Some(i) = (0..self.state.x.len()).find(|&i| {
            self.state.x[i]
                .iter()
                .chain(&self.state.v[i])
                .any(|c| !c.is_finite())
        }) {
            return Err(SimError::Unstable {
                step,
                reason: format!("vertex {i} is not finite"),
            });
        }
        Ok(iterations)
    }

    /// The current energy, or `Unstable` when the total exceeds the initial energy by more
    /// than the blow-up threshold.
    pub fn check_energy(&self, sphere: Option<&Sphere>) -> Result<Energy, SimError> {
        let e = self.energy(sphere);
        if !e.total().is_finite() || e.total() - self.e0 > self.e_limit {
            return Err(SimError::Unstable {
                step: self.steps.saturating_sub(1),
                reason: format!(
                    "total energy {:.4e} exceeds the initial {:.4e} by more than {:.4e}",
                    e.total(),
                    self.e0,
                    self.e_limit
                ),
            });
        }
        Ok(e)
    }
}
