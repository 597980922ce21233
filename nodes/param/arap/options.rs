//! Settings of `arap_parameterize` and the constants of its fold-free line search, kept
//! together so that every tuning knob of the solver is in one place.

/// Settings of `arap_parameterize`.
#[derive(Clone, Debug)]
pub struct ArapOptions {
    /// Maximum number of local/global iterations.
    pub iterations: usize,
    /// Stop when an iteration lowers the energy by less than this fraction of it.
    pub tolerance: f64,
    /// Never accept a step that flips or flattens a triangle (needs a fold-free start).
    pub injective: bool,
    /// The vertex kept at its initial UV (translation gauge); `None`: the first vertex.
    /// Every other connected component pins its first vertex.
    pub pin: Option<usize>,
    /// `None`: ARAP (rotations). `Some(λ)`: the hybrid model of Liu et al. 2008 §4.3, where
    /// `λ = 0` is ASAP's similarity and `λ → ∞` tends to ARAP.
    pub lambda: Option<f64>,
    /// When the fold-free mode refactors the Laplacian after stiffening triangles.
    pub refactor: RefactorSchedule,
    /// Fold-free mode: rings around the blocking triangles re-solved locally with the
    /// stiffened weights (see `local_resolve`) before any refactorization; 0 turns it off.
    pub local_rings: usize,
}

impl Default for ArapOptions {
    fn default() -> Self {
        ArapOptions {
            iterations: 100,
            tolerance: 1e-6,
            injective: true,
            pin: None,
            lambda: None,
            refactor: RefactorSchedule::default(),
            local_rings: LOCAL_RINGS,
        }
    }
}

/// When the fold-free mode refreshes the Cholesky factor of the reweighted Laplacian.
///
/// Stiffened weights accumulate every blocked iteration, but the numeric refactorization
/// (the costliest part of an iteration) runs only when one of the triggers below fires; in
/// between, the stale factor still gives a descent direction (any SPD matrix does) and the
/// max-step limit and Armijo's test keep the iteration fold-free and monotone. A triangle
/// that keeps blocking keeps stiffening meanwhile, so it is frozen once the factor is fresh.
/// Besides the triggers below, the factor is refreshed when the triangle that limits the
/// step is already below its area margin, or when the orientation-preserving step vanishes.
///
/// The default refactors once in every blocked iteration: waiting for several blocked
/// iterations makes each iteration cheaper, but the stale-factor steps barely move, so the
/// energy at equal time is worse (`docs/charts/arap_iterations.md`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefactorSchedule {
    /// Refactorizations allowed per iteration (each followed by a new solve and max-step pass).
    pub per_iteration: usize,
    /// Refactor once the step has been blocked (cut below half the best step) this many
    /// iterations running with stiffened weights pending.
    pub blocked_run: usize,
    /// ... or as soon as the triangles stiffened since the last refactorization exceed this
    /// fraction of all triangles.
    pub growth: f64,
}

impl Default for RefactorSchedule {
    fn default() -> Self {
        RefactorSchedule {
            per_iteration: 1,
            blocked_run: 0,
            growth: 0.0,
        }
    }
}

/// Default `ArapOptions::local_rings`.
pub const LOCAL_RINGS: usize = 2;
/// Local re-solves tried per iteration before falling back to the refactorization schedule...
pub(super) const LOCAL_ROUNDS: usize = 5;
/// ... unless one leaves the orientation-preserving step (as a fraction of the best step)
/// below this fraction of what it was before it: the stiffened region then blocks more, not
/// less, and the rounds stop for a refactorization. On camelhead, in the first iteration
/// (3 rounds, then a refactorization) the fraction fell 0.35 -> 0.22 -> 0.10 -> 0.06, while
/// rounds that unblock raise it every time (0.08 -> 0.23 -> 0.49 -> 0.71 in iteration 5).
pub(super) const LOCAL_GIVE_UP: f64 = 0.5;

/// A local re-solve whose region holds more than this fraction of the free vertices is not
/// done: the blocked step is left to a refactorization of the whole Laplacian, which then
/// costs about as much as one local round. On camelhead and camel_b the regions hold at most
/// 9 % of the vertices; on a closed bunny cut open at its base (`assets/meshes/bunny_base.obj`,
/// issue 29) 22-88 %, where 4-5 such rounds per iteration took two thirds of the run.
pub(super) const LOCAL_MAX_FRACTION: f64 = 0.15;

/// Armijo's sufficient-decrease constant.
pub(super) const ARMIJO_C: f64 = 1e-4;
/// Fraction of the largest orientation-preserving step that is tried first
/// (Smith & Schaefer 2015 back off from the singularity the same way).
pub(super) const STEP_SAFETY: f64 = 0.9;
/// Halvings of the step before giving up.
pub(super) const MAX_BACKTRACKS: usize = 40;
/// When the orientation-preserving step is below this fraction of the best step along the
/// direction, the blocking triangles are stiffened and the direction recomputed.
pub(super) const BLOCKED_STEP: f64 = 0.5;
/// Factor applied to a blocking triangle's weight.
pub(super) const REWEIGHT_FACTOR: f64 = 10.0;
/// Largest weight.
pub(super) const MAX_WEIGHT: f64 = 1e8;
/// Fold-free steps keep every triangle's UV area above this fraction of its 3-D area (after
/// scaling the start's layout to the 3-D area), or above half its current area if already
/// smaller, so that blocked triangles are not squeezed towards zero area...
pub(super) const AREA_MARGIN: f64 = 1e-3;
/// ... and never below this fraction of its 3-D area (or half its area in the start if that
/// is smaller): without a fixed floor a triangle could halve its area every iteration and
/// collapse over many iterations.
pub(super) const AREA_FLOOR: f64 = 1e-6;
/// Below this orientation-preserving step length the iteration is stalled.
pub(super) const MIN_STEP: f64 = 1e-12;
