//! `mass_spring`: cloth as a mass-spring system (course assignment 8), stepped frame by frame
//! with one of four integrators: `semi_implicit` (symplectic Euler, conditionally stable),
//! `implicit` (backward Euler by Newton's method on its variational form, stable at large
//! steps), `quasi_newton` (the same backward Euler by L-BFGS with a prefactored initial
//! Hessian, Liu et al. 2017: fast on stiff cloth) or `projective` (Liu et al. 2013's
//! local/global solver with a prefactored matrix).
//!
//! The core is plain data (`Model`, `State`, in `springs`) and a `Simulator` (`simulator`)
//! that advances it step by step and detects blow-ups; the node (`mass_spring`) wraps it with
//! frame-to-frame state, fixed-vertex selections (`cgnodes_geometry::vertex_select`) and a
//! sphere collider that may move along keyframes (`keyframes`).

// Numerical kernels index several parallel arrays (positions, velocities, masses, flags) by
// vertex; index loops read closer to the formulas than zipped iterators.
#![allow(clippy::needless_range_loop)]

pub mod control;
mod frame_run;
pub mod implicit;
pub mod keyframes;
// The node lives in a file named after its node type, which is also this domain's name.
#[allow(clippy::module_inception)]
pub mod mass_spring;
pub mod newton_direct;
pub mod newton_pcg;
pub mod projective;
pub mod quasi_newton;
pub mod semi_implicit;
pub mod simulator;
pub mod springs;

pub use control::PairError;
pub use implicit::{Implicit, LinearSolver, NewtonError, NewtonOptions, NewtonProfile};
pub use keyframes::{keyframed_center, parse_keyframes};
pub use mass_spring::LOG_COLUMNS;
pub use newton_pcg::Preconditioner;
pub use projective::Projective;
pub use quasi_newton::{QuasiNewton, QuasiNewtonOptions};
pub use semi_implicit::SemiImplicit;
pub use simulator::{
    energy_scale, Method, MoveError, SetupError, SimError, Simulator, SolverOptions, StepLog,
};
pub use springs::{
    energy, springs_from_mesh, Energy, Model, ModelError, Sphere, SpringKinds, Springs, State,
};

use cgnodes_api::registry::Registry;

/// Registers `mass_spring`.
pub fn register(r: &mut Registry) {
    mass_spring::register(r);
}
