//! `arap` and `arap_hybrid`: the local/global parameterization of Liu et al. 2008
//! ("A Local/Global Approach to Mesh Parameterization"), with an optional fold-free line
//! search (Smith & Schaefer 2015).
//!
//! Each iteration fits a target per triangle to the current Jacobian (local step: closed-form
//! 2x2 decomposition, in parallel), then solves for the UVs that best follow the targets
//! (global step: the cotangent Laplacian, factored once, both coordinates in one solve).
//! In fold-free mode the move towards the global solution is cut to the largest step that
//! keeps every triangle's orientation, then backed off until the energy drops (Armijo).

use super::frames::{cross2, local_step, Similarity, TriangleFrames, PAR_CHUNK};
use super::injective::{area_coefficients, orientation_and_flips, smallest_positive_root};
use super::{component_of, init_uvs, uv_outputs, StopReason};
use crate::nodes::linalg::SpdFactor;
use crate::prelude::*;
use faer::sparse::{SparseColMat, SymbolicSparseColMat, Triplet};
use faer::{Mat, Par};
use rayon::prelude::*;
use std::time::Instant;

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
/// The default refactors once in every blocked iteration: on camelhead, waiting for 4
/// blocked iterations made each iteration cheaper (9 against 13 ms) but the stale-factor
/// steps barely moved, so the energy at equal time was worse (0.6193 after 1.0 s against
/// 0.6152 after 0.87 s; `docs/charts/arap_iterations.md`).
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

/// One row of the convergence log.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArapIteration {
    /// 0 for the initial UVs.
    pub iteration: usize,
    /// Area-weighted mean energy, `Σ A_t (|J_t - L_t|² + 2λ(s_t²-1)²) / Σ A_t`
    /// (for ARAP: `Σ A ((σ1-1)² + (σ2-1)²) / Σ A`).
    pub energy: f64,
    /// Triangles whose orientation disagrees with the majority (or are degenerate).
    pub flips: usize,
    /// Time since the call started, in milliseconds (setup and factorization included).
    pub elapsed_ms: f64,
    /// Length of the step taken along the search direction (1: the full global step;
    /// 0 for the initial row).
    pub step: f64,
    /// Whether the step was cut short to keep every triangle's orientation.
    pub blocked: bool,
    /// Numeric refactorizations of the reweighted Laplacian during this iteration.
    pub refactors: usize,
}

/// What `arap_parameterize` returns.
#[derive(Clone, Debug)]
pub struct ArapResult {
    /// One UV per vertex.
    pub uv: Vec<[f64; 2]>,
    /// Row 0 is the start; one row per accepted iteration.
    pub log: Vec<ArapIteration>,
    /// Why the iterations stopped.
    pub stop_reason: StopReason,
    /// Flipped triangles at the end.
    pub flips: usize,
    /// Final energy (as in the log).
    pub energy: f64,
    /// Times a triangle's weight was raised by the fold-free mode (0: plain local/global).
    pub reweighted: usize,
    /// Numeric refactorizations after reweighting (the initial factorization not counted).
    pub refactors: usize,
    /// Local stiffened re-solves of blocked steps (`ArapOptions::local_rings`).
    pub local_solves: usize,
    /// Details of a `NoProgress` stop (empty otherwise).
    pub stop_detail: String,
}

/// Default `ArapOptions::local_rings`.
pub const LOCAL_RINGS: usize = 2;
/// Local re-solves tried per iteration before falling back to the refactorization schedule...
const LOCAL_ROUNDS: usize = 5;
/// ... unless one leaves the orientation-preserving step (as a fraction of the best step)
/// below this fraction of what it was before it: the stiffened region then blocks more, not
/// less, and the rounds stop for a refactorization. On camelhead, in the first iteration
/// (3 rounds, then a refactorization) the fraction fell 0.35 -> 0.22 -> 0.10 -> 0.06, while
/// rounds that unblock raise it every time (0.08 -> 0.23 -> 0.49 -> 0.71 in iteration 5).
const LOCAL_GIVE_UP: f64 = 0.5;

/// Armijo's sufficient-decrease constant.
const ARMIJO_C: f64 = 1e-4;
/// Fraction of the largest orientation-preserving step that is tried first
/// (Smith & Schaefer 2015 back off from the singularity the same way).
const STEP_SAFETY: f64 = 0.9;
/// Halvings of the step before giving up.
const MAX_BACKTRACKS: usize = 40;
/// When the orientation-preserving step is below this fraction of the best step along the
/// direction, the blocking triangles are stiffened and the direction recomputed.
const BLOCKED_STEP: f64 = 0.5;
/// Factor applied to a blocking triangle's weight.
const REWEIGHT_FACTOR: f64 = 10.0;
/// Largest weight.
const MAX_WEIGHT: f64 = 1e8;
/// Fold-free steps keep every triangle's UV area above this fraction of its 3-D area (after
/// scaling the start's layout to the 3-D area), or above half its current area if already
/// smaller, so that blocked triangles are not squeezed towards zero area...
const AREA_MARGIN: f64 = 1e-3;
/// ... and never below this fraction of its 3-D area (or half its area in the start if that
/// is smaller): without a fixed floor a triangle could halve its area every iteration and
/// collapse over many iterations.
const AREA_FLOOR: f64 = 1e-6;
/// Below this orientation-preserving step length the iteration is stalled.
const MIN_STEP: f64 = 1e-12;

/// ARAP (or hybrid) parameterization of a triangle mesh from initial UVs, libigl style.
///
/// The energy is `Σ_t A_t |J_t - L_t|²`, which equals Liu et al.'s
/// `½ Σ_t Σ_(i,j) cot θ_ij |(u_i - u_j) - L_t (x_i - x_j)|²` (eq. 3). The global step solves
/// `Δ u = b` (eq. 6) with the cotangent Laplacian `Δ` restricted to the free vertices, factored
/// once. Energy never increases: the global step minimizes a convex quadratic in the UVs whose
/// value at the current UVs is the current energy, so every step length in `(0, 1]` along it
/// lowers it; the Armijo test only guards against rounding.
pub fn arap_parameterize(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    init_uv: &[[f64; 2]],
    opts: &ArapOptions,
) -> Result<ArapResult, NodeError> {
    // The loop runs several short parallel passes per iteration. Run from a thread outside
    // rayon's pool, each pass is injected into the pool and waited for, a round trip through
    // the OS per pass; on a pool thread the passes are split in place. camel_b fold-free, 30
    // iterations: 0.59-0.69 -> 0.40-0.48 ms per iteration (median of 10 runs, 3 alternations).
    rayon::scope(|_| iterate(positions, triangles, init_uv, opts))
}

/// `arap_parameterize` on a rayon pool thread.
fn iterate(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    init_uv: &[[f64; 2]],
    opts: &ArapOptions,
) -> Result<ArapResult, NodeError> {
    let start = Instant::now();
    let n = positions.len();
    if init_uv.len() != n {
        return Err(NodeError::invalid(
            "init",
            format!(
                "initial UVs have {} entries but the mesh has {n} vertices",
                init_uv.len()
            ),
        ));
    }
    if let Some(v) = init_uv
        .iter()
        .position(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return Err(NodeError::invalid(
            "init",
            format!("initial UV of vertex {v} is not finite"),
        ));
    }
    if triangles.is_empty() {
        return Err(NodeError::invalid("mesh", "mesh has no triangles"));
    }
    if !(opts.tolerance >= 0.0 && opts.tolerance.is_finite()) {
        return Err(NodeError::invalid(
            "tolerance",
            "tolerance must be finite and >= 0",
        ));
    }
    if let Some(l) = opts.lambda {
        if !(l >= 0.0 && l.is_finite()) {
            return Err(NodeError::invalid(
                "lambda",
                "lambda must be finite and >= 0",
            ));
        }
    }
    if let Some(p) = opts.pin {
        if p >= n {
            return Err(NodeError::invalid(
                "pin",
                format!("pin {p} is not a vertex (the mesh has {n})"),
            ));
        }
    }
    let frames =
        TriangleFrames::new(positions, triangles).map_err(|e| NodeError::invalid("mesh", e))?;
    let m = frames.len();
    let lambda = opts.lambda;

    // Orientation of the start; work counter-clockwise, mirroring a clockwise start.
    let (orient, flips0) = orientation_and_flips(&frames, init_uv);
    if opts.injective && flips0 > 0 {
        return Err(NodeError::new(
            ErrorKind::Folded,
            format!(
                "the initial UVs have {flips0} flipped or degenerate triangles; fold-free ARAP needs a fold-free start (the default Tutte initialization is one), or set injective: false"
            ),
        ));
    }
    let mut uv: Vec<[f64; 2]> = init_uv.iter().map(|p| [p[0], orient * p[1]]).collect();

    // Fixed vertices: one pin per connected component, and vertices in no triangle.
    let fixed = fixed_vertices(n, triangles, opts.pin);
    let mut free_index = vec![u32::MAX; n];
    let mut free_vertices = Vec::new();
    for v in 0..n {
        if !fixed[v] {
            free_index[v] = free_vertices.len() as u32;
            free_vertices.push(v);
        }
    }
    let nf = free_vertices.len();

    // Cotangent Laplacian on the free vertices (lower triangle), each entry tagged with its
    // triangle so that the fold-free mode can reweight triangles (see `reweight`).
    let (trip, trip_tri) = laplacian_triplets(&frames, &free_index);
    let singular = |e: String| {
        NodeError::singular(format!(
            "the cotangent Laplacian could not be factored ({e}); the mesh may have nearly degenerate triangles"
        ))
    };
    let mut factor = if nf > 0 {
        let mut f = SpdFactor::new(nf, &trip, Par::Seq).map_err(singular)?;
        f.prepare_many_solves();
        Some(f)
    } else {
        None
    };
    let (row_of, row_vertex) = factor.as_ref().map_or((Vec::new(), Vec::new()), |f| {
        elimination_rows(f, &free_index)
    });
    let mut weights = vec![1.0; if opts.injective { m } else { 0 }];
    let sched = opts.refactor;
    // per triangle, twice the UV area of the margin and of the hard floor (see AREA_MARGIN)
    let floor2: Vec<[f64; 2]> = if opts.injective {
        let a2: Vec<f64> = (0..m).map(|t| frames.signed_area2(t, &uv)).collect();
        let ratio = a2.iter().sum::<f64>() / (2.0 * frames.total_area);
        a2.iter()
            .zip(&frames.area)
            .map(|(&a2, &area)| {
                let a3 = 2.0 * area * ratio;
                [AREA_MARGIN * a3, (AREA_FLOOR * a3).min(0.5 * a2)]
            })
            .collect()
    } else {
        Vec::new()
    };

    let corner_w = corner_weights(&frames);

    let total_area = frames.total_area;
    let mut targets: Vec<Similarity> = vec![[1.0, 0.0]; m];
    let mut trial_targets: Vec<Similarity> = vec![[1.0, 0.0]; m];
    let (e_sum, flips) = evaluate(&frames, &uv, lambda, &mut targets);
    let mut energy = e_sum / total_area;
    let mut log = vec![ArapIteration {
        iteration: 0,
        energy,
        flips,
        elapsed_ms: ms(start),
        step: 0.0,
        blocked: false,
        refactors: 0,
    }];
    let mut stop = StopReason::Iterations;
    let mut rhs = Mat::<f64>::zeros(nf, 2);
    let mut gradient = Mat::<f64>::zeros(nf, 2);
    let mut gradient_halves = [Vec::new(), Vec::new()];
    let mut reweighted = 0usize;
    let mut refactors = 0usize;
    // stiffenings not yet in the factor, and blocked iterations since the last refactor
    let (mut pending, mut blocked_run) = (0usize, 0usize);
    let mut detail = String::new();
    let mut d = vec![[0.0; 2]; n];
    let mut trial = uv.clone();
    let mut step_limits = StepLimits {
        limits: vec![f64::INFINITY; floor2.len()],
        terms: vec![[0.0; 2]; floor2.len()],
        blocks: vec![BlockSum::default(); floor2.len().div_ceil(SUM_BLOCK)],
        dirty: vec![false; floor2.len().div_ceil(SUM_BLOCK)],
        floor2,
    };
    let mut touched: Vec<u32> = Vec::new();
    let mut local_solves = 0usize;
    let mut mark = vec![u32::MAX; if opts.injective { n } else { 0 }];
    let mut seen = vec![false; if opts.injective { m } else { 0 }];
    let adjacency = if opts.injective && opts.local_rings > 0 {
        vertex_triangles(n, &frames.triangles)
    } else {
        (Vec::new(), Vec::new())
    };
    let mut it = 0;
    while it < opts.iterations {
        let Some(factor) = factor.as_mut() else {
            stop = StopReason::Tolerance;
            break;
        };
        it += 1;
        // Global step, written as a preconditioned gradient step: d = -Δ_W⁻¹ ∇E. With unit
        // weights this is exactly Liu et al.'s global solve minus the current UVs;
        // ∇E at vertex i is Σ_t Σ_j cot θ_ij ((u_i - u_j) - L_t (x_i - x_j)) (eq. 6).
        gradient_into(
            &frames,
            &corner_w,
            &targets,
            &uv,
            &row_of,
            &mut gradient_halves,
            &mut gradient,
        );
        descent_direction(factor, &gradient, &mut rhs, &row_vertex, &mut d);

        // Line search.
        let mut step = 1.0;
        let mut slope = 0.0; // derivative of the energy along d at step 0 (negative)
        let mut blocked = false;
        let mut iter_refactors = 0;
        if opts.injective {
            let mut dir = step_limits.directional(&frames, &uv, &d, &targets, None);
            // A blocked step is first reshaped locally: the blocking triangles are stiffened
            // and the rings around them re-solved with the stiffened weights, the rest of
            // the global step kept (`local_resolve`); refactoring the whole Laplacian (below)
            // is left for what that does not unblock.
            let mut local = false;
            if opts.local_rings > 0 {
                for _ in 0..LOCAL_ROUNDS {
                    if STEP_SAFETY * dir.max_step >= BLOCKED_STEP * dir.best_step {
                        break;
                    }
                    let before = dir.max_step / dir.best_step;
                    let changed = reweight(&step_limits.limits, dir.best_step, &mut weights);
                    pending += changed;
                    reweighted += changed;
                    let solved = local_resolve(
                        &frames,
                        &weights,
                        &step_limits.limits,
                        dir.best_step,
                        opts.local_rings,
                        &row_of,
                        &gradient,
                        &adjacency,
                        &mut mark,
                        &mut seen,
                        &mut touched,
                        &mut d,
                    );
                    if solved.is_err() {
                        break;
                    }
                    dir = step_limits.directional(&frames, &uv, &d, &targets, Some(&touched));
                    local = true;
                    local_solves += 1;
                    if dir.max_step / dir.best_step < LOCAL_GIVE_UP * before {
                        break;
                    }
                }
                if local && (dir.slope.is_nan() || dir.slope >= 0.0) {
                    // the local re-solve lost the descent: back to the global direction
                    descent_direction(factor, &gradient, &mut rhs, &row_vertex, &mut d);
                    dir = step_limits.directional(&frames, &uv, &d, &targets, None);
                }
            }
            loop {
                if STEP_SAFETY * dir.max_step >= BLOCKED_STEP * dir.best_step {
                    blocked_run = 0;
                    break;
                }
                // Blocked: stiffen the triangles that the step would flip (weights accumulate;
                // the factor is refreshed on the schedule's triggers only).
                if iter_refactors == 0 {
                    blocked_run += 1;
                }
                let changed = reweight(&step_limits.limits, dir.best_step, &mut weights);
                pending += changed;
                reweighted += changed;
                let due = blocked_run >= sched.blocked_run
                    || pending as f64 >= sched.growth * m as f64
                    || dir.squeezed
                    || dir.max_step < MIN_STEP;
                if pending == 0 || !due || iter_refactors >= sched.per_iteration {
                    break;
                }
                factor
                    .refactor_with(
                        trip.len(),
                        |k| trip[k].val * weights[trip_tri[k] as usize],
                        Par::Seq,
                    )
                    .map_err(singular)?;
                (pending, blocked_run) = (0, 0);
                iter_refactors += 1;
                descent_direction(factor, &gradient, &mut rhs, &row_vertex, &mut d);
                dir = step_limits.directional(&frames, &uv, &d, &targets, None);
            }
            refactors += iter_refactors;
            slope = dir.slope / total_area; // per unit area, like `energy`
            step = dir.best_step.min(STEP_SAFETY * dir.max_step);
            blocked = STEP_SAFETY * dir.max_step < dir.best_step;
            if dir.max_step < MIN_STEP {
                stop = StopReason::NoProgress;
                detail = format!(
                    "orientation-preserving step {:.3e} at iteration {it}",
                    dir.max_step
                );
                break;
            }
            if slope.is_nan() || slope >= 0.0 {
                // zero: already stationary for these targets; positive/NaN: no descent left
                stop = if slope == 0.0 {
                    StopReason::Tolerance
                } else {
                    StopReason::NoProgress
                };
                detail = format!("slope {slope:.3e} along the search direction at iteration {it}");
                break;
            }
        }
        let mut accepted = None;
        let first_step = step;
        for _ in 0..MAX_BACKTRACKS {
            if step <= 0.0 || !step.is_finite() {
                break;
            }
            trial
                .par_iter_mut()
                .zip(uv.par_iter().zip(d.par_iter()))
                .with_min_len(PAR_CHUNK)
                .for_each(|(o, (u, dv))| *o = [u[0] + step * dv[0], u[1] + step * dv[1]]);
            let (e_sum, fl) = evaluate(&frames, &trial, lambda, &mut trial_targets);
            let e = e_sum / total_area;
            let ok_orient = !opts.injective || fl == 0;
            if ok_orient && e.is_finite() && e <= energy + ARMIJO_C * step * slope {
                accepted = Some((e, fl));
                break;
            }
            step *= 0.5;
        }
        let Some((e_new, fl)) = accepted else {
            stop = StopReason::NoProgress;
            detail = format!(
                "line search failed at iteration {it} (slope {slope:.3e}, first step {first_step:.3e})"
            );
            break;
        };
        std::mem::swap(&mut uv, &mut trial);
        std::mem::swap(&mut targets, &mut trial_targets);
        let e_old = energy;
        energy = e_new;
        log.push(ArapIteration {
            iteration: it,
            energy,
            flips: fl,
            elapsed_ms: ms(start),
            step,
            blocked,
            refactors: iter_refactors,
        });
        if e_old - energy <= opts.tolerance * e_old {
            // a step cut short by a triangle about to flip is a stall, not convergence
            stop = if blocked {
                StopReason::NoProgress
            } else {
                StopReason::Tolerance
            };
            break;
        }
    }
    if orient < 0.0 {
        for p in &mut uv {
            p[1] = -p[1];
        }
    }
    let flips = log.last().map_or(0, |r| r.flips);
    Ok(ArapResult {
        uv,
        log,
        stop_reason: stop,
        flips,
        energy,
        reweighted,
        refactors,
        local_solves,
        stop_detail: detail,
    })
}

fn ms(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

/// Local step for every triangle at `uv` (targets written to `targets`), returning the
/// area-weighted energy sum and the number of triangles with `det J <= 0`.
fn evaluate(
    frames: &TriangleFrames,
    uv: &[[f64; 2]],
    lambda: Option<f64>,
    targets: &mut [Similarity],
) -> (f64, usize) {
    // fixed chunks summed in order: the result does not depend on rayon's scheduling
    let parts: Vec<(f64, usize)> = targets
        .par_chunks_mut(PAR_CHUNK)
        .enumerate()
        .map(|(c, chunk)| {
            let (mut e_sum, mut flips) = (0.0, 0);
            for (k, out) in chunk.iter_mut().enumerate() {
                let t = c * PAR_CHUNK + k;
                let j = frames.jacobian(t, uv);
                let (l, e) = local_step(&j, lambda);
                *out = l;
                let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
                e_sum += frames.area[t] * e;
                flips += usize::from(det <= 0.0);
            }
            (e_sum, flips)
        })
        .collect();
    parts.iter().fold((0.0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// What the energy does along a direction `δ` with the targets held fixed.
struct Directional {
    /// `dE/ds` at `s = 0`: `Σ 2 A <J(uv) - L, J(δ)>`.
    slope: f64,
    /// Minimizer of the quadratic `E + s·slope + s²·Σ A |J(δ)|²` (1 for the global step).
    best_step: f64,
    /// Largest step keeping every triangle's orientation.
    max_step: f64,
    /// Whether the triangle that sets `max_step` is already below its area margin (it is
    /// being squeezed towards its hard floor: stiffening it cannot wait).
    squeezed: bool,
}

/// Triangles per block of `StepLimits::blocks` (divides `PAR_CHUNK`).
const SUM_BLOCK: usize = 256;
const _: () = assert!(PAR_CHUNK.is_multiple_of(SUM_BLOCK));

/// Sums of `StepLimits::terms` and the smallest limit (and its triangle) over one block of
/// `SUM_BLOCK` triangles.
#[derive(Clone, Copy, Debug)]
struct BlockSum {
    slope: f64,
    curv: f64,
    min_limit: f64,
    arg: usize,
}

impl Default for BlockSum {
    fn default() -> Self {
        BlockSum {
            slope: 0.0,
            curv: 0.0,
            min_limit: f64::INFINITY,
            arg: usize::MAX,
        }
    }
}

impl BlockSum {
    /// The block of triangles starting at `first`, summed in order.
    fn of(first: usize, limits: &[f64], terms: &[[f64; 2]]) -> BlockSum {
        let mut b = BlockSum::default();
        for (k, (&lim, tm)) in limits.iter().zip(terms).enumerate() {
            b.slope += tm[0];
            b.curv += tm[1];
            if lim < b.min_limit {
                (b.min_limit, b.arg) = (lim, first + k);
            }
        }
        b
    }
}

/// Per-triangle state of the fold-free line search: each triangle's area floors, and its
/// orientation limit and slope/curvature terms from the last `directional` pass, with their
/// sums per block of `SUM_BLOCK` triangles, so that a pass over a few changed triangles
/// re-sums only their blocks (on camelhead the full re-sum was half the time of a local
/// re-solve's pass).
struct StepLimits {
    /// Twice the UV area of the margin and of the hard floor (see `AREA_MARGIN`).
    floor2: Vec<[f64; 2]>,
    /// The step at which the triangle's UV area would reach its floor.
    limits: Vec<f64>,
    /// `[2 A <J(uv) - L, J(δ)>, A |J(δ)|²]` (see `line_terms`).
    terms: Vec<[f64; 2]>,
    /// Sums per block of triangles.
    blocks: Vec<BlockSum>,
    /// Scratch: blocks with a changed triangle (all `false` between calls).
    dirty: Vec<bool>,
}

impl StepLimits {
    /// One parallel pass over the triangles: slope and curvature of the targets' quadratic
    /// along `dir`, and each triangle's orientation limit: the step at which its UV area
    /// would drop to its floor, `max(hard, min(margin, half the current area))`. With
    /// `changed`, `dir` differs from the last call only on those triangles: only their
    /// terms are recomputed. Sums are taken per fixed block, blocks in order, so the
    /// result depends neither on rayon's scheduling nor on which triangles were recomputed.
    fn directional(
        &mut self,
        frames: &TriangleFrames,
        uv: &[[f64; 2]],
        dir: &[[f64; 2]],
        targets: &[Similarity],
        changed: Option<&[u32]>,
    ) -> Directional {
        let floor2 = &self.floor2;
        match changed {
            Some(list) => {
                for &t in list {
                    let t = t as usize;
                    let ([c0, c1, c2], tm) = line_terms(frames, t, uv, dir, targets, floor2);
                    (self.limits[t], self.terms[t]) = (smallest_positive_root(c0, c1, c2), tm);
                    self.dirty[t / SUM_BLOCK] = true;
                }
                for (b, dirty) in self.dirty.iter_mut().enumerate() {
                    if std::mem::take(dirty) {
                        let range = b * SUM_BLOCK..((b + 1) * SUM_BLOCK).min(self.limits.len());
                        self.blocks[b] = BlockSum::of(
                            range.start,
                            &self.limits[range.clone()],
                            &self.terms[range],
                        );
                    }
                }
            }
            None => self
                .limits
                .par_chunks_mut(PAR_CHUNK)
                .zip(self.terms.par_chunks_mut(PAR_CHUNK))
                .zip(self.blocks.par_chunks_mut(PAR_CHUNK / SUM_BLOCK))
                .enumerate()
                .for_each(|(ci, ((lims, ts), blocks))| {
                    // the roots in a second loop over the block: one triangle's root is a
                    // chain of a square root and two divisions, which a loop of roots alone
                    // overlaps across triangles
                    let mut c = [[0.0; SUM_BLOCK]; 3];
                    for (b, ((blk, l), tm)) in blocks
                        .iter_mut()
                        .zip(lims.chunks_mut(SUM_BLOCK))
                        .zip(ts.chunks_mut(SUM_BLOCK))
                        .enumerate()
                    {
                        let first = ci * PAR_CHUNK + b * SUM_BLOCK;
                        for (k, tmk) in tm.iter_mut().enumerate() {
                            let coef;
                            (coef, *tmk) = line_terms(frames, first + k, uv, dir, targets, floor2);
                            (c[0][k], c[1][k], c[2][k]) = (coef[0], coef[1], coef[2]);
                        }
                        let [c0, c1, c2] = &c;
                        for (lim, ((c0, c1), c2)) in l.iter_mut().zip(c0.iter().zip(c1).zip(c2)) {
                            *lim = smallest_positive_root(*c0, *c1, *c2);
                        }
                        *blk = BlockSum::of(first, l, tm);
                    }
                }),
        }
        reduce_directional(frames, uv, floor2, &self.blocks)
    }
}

/// One triangle's part of `directional`: the coefficients of twice its UV area above its
/// floor along the direction (`area_coefficients`; the orientation limit is their smallest
/// positive root) and its terms of the slope and curvature, `[2 A <J(uv) - L, J(δ)>, A |J(δ)|²]`.
fn line_terms(
    frames: &TriangleFrames,
    t: usize,
    uv: &[[f64; 2]],
    dir: &[[f64; 2]],
    targets: &[Similarity],
    floor2: &[[f64; 2]],
) -> ([f64; 3], [f64; 2]) {
    // each corner's UV and direction loaded once
    let e = frames.edges(t, uv);
    let de = frames.edges(t, dir);
    let j0 = frames.jacobian_of_edges(t, e[0], e[1]);
    let jd = frames.jacobian_of_edges(t, de[0], de[1]);
    let [a, b] = targets[t];
    let l = [[a, -b], [b, a]];
    let (mut g, mut c) = (0.0, 0.0);
    for r in 0..2 {
        for k in 0..2 {
            g += (j0[r][k] - l[r][k]) * jd[r][k];
            c += jd[r][k] * jd[r][k];
        }
    }
    let [margin, hard] = floor2[t];
    let a2 = cross2(e[0], e[1]);
    let floor = hard.max(margin.min(0.5 * a2));
    let coef = area_coefficients(e, de, 1.0, floor);
    (coef, [2.0 * frames.area[t] * g, frames.area[t] * c])
}

/// Sums of the per-triangle terms (block sums, blocks in order) and the smallest limit.
fn reduce_directional(
    frames: &TriangleFrames,
    uv: &[[f64; 2]],
    floor2: &[[f64; 2]],
    blocks: &[BlockSum],
) -> Directional {
    let (mut slope, mut curv) = (0.0, 0.0);
    let (mut max_step, mut arg) = (f64::INFINITY, usize::MAX);
    for b in blocks {
        slope += b.slope;
        curv += b.curv;
        if b.min_limit < max_step {
            (max_step, arg) = (b.min_limit, b.arg);
        }
    }
    let squeezed = arg != usize::MAX && frames.signed_area2(arg, uv) < floor2[arg][0];
    let best_step = if curv > 0.0 {
        -slope / (2.0 * curv)
    } else {
        0.0
    };
    Directional {
        slope,
        best_step: best_step.max(0.0),
        max_step,
        squeezed,
    }
}

/// The gradient, the solves and the local re-solves keep the free vertices in the factor's
/// elimination order, so that a solve needs no permuted copies
/// (`SpdFactor::solve_in_elimination_order`). Returns each vertex's row in that order
/// (`u32::MAX` when fixed, i.e. `free_index[v] == u32::MAX`) and the vertex of each row.
fn elimination_rows(factor: &SpdFactor, free_index: &[u32]) -> (Vec<u32>, Vec<usize>) {
    let position = factor.elimination_position();
    let row_of: Vec<u32> = free_index
        .iter()
        .map(|&f| {
            if f == u32::MAX {
                f
            } else {
                position[f as usize] as u32
            }
        })
        .collect();
    let mut row_vertex = vec![0usize; position.len()];
    for (v, &r) in row_of.iter().enumerate() {
        if r != u32::MAX {
            row_vertex[r as usize] = v;
        }
    }
    (row_of, row_vertex)
}

/// `d = -Δ_W⁻¹ g` for the gradient `g` (one row per free vertex, in the factor's elimination
/// order; `rhs` is the solve's scratch), scattered to the free vertices (`row_vertex[k]`: the
/// vertex of row `k`); pinned vertices keep their zero direction.
fn descent_direction(
    factor: &SpdFactor,
    gradient: &Mat<f64>,
    rhs: &mut Mat<f64>,
    row_vertex: &[usize],
    d: &mut [[f64; 2]],
) {
    rhs.copy_from(gradient);
    factor.solve_in_elimination_order(rhs.as_mut());
    for (k, &v) in row_vertex.iter().enumerate() {
        d[v] = [-rhs[(k, 0)], -rhs[(k, 1)]];
    }
}

/// The cotangent Laplacian on the free vertices (lower-triangle triplets; `free_index` maps a
/// vertex to its row, `u32::MAX` when pinned), each entry tagged with its triangle so that the
/// fold-free mode can reweight triangles (see `reweight`).
fn laplacian_triplets(
    frames: &TriangleFrames,
    free_index: &[u32],
) -> (Vec<Triplet<usize, usize, f64>>, Vec<u32>) {
    let m = frames.len();
    let mut trip: Vec<Triplet<usize, usize, f64>> = Vec::with_capacity(9 * m);
    let mut trip_tri: Vec<u32> = Vec::with_capacity(9 * m);
    for t in 0..m {
        let tri = frames.triangles[t];
        for k in 0..3 {
            let (i, j) = (tri[(k + 1) % 3] as usize, tri[(k + 2) % 3] as usize);
            let w = frames.cot[t][k];
            let (fi, fj) = (free_index[i], free_index[j]);
            let mut push = |r: u32, c: u32, v: f64| {
                trip.push(Triplet::new(r as usize, c as usize, v));
                trip_tri.push(t as u32);
            };
            if fi != u32::MAX {
                push(fi, fi, w);
            }
            if fj != u32::MAX {
                push(fj, fj, w);
            }
            if fi != u32::MAX && fj != u32::MAX {
                push(fi.max(fj), fi.min(fj), -w);
            }
        }
    }
    (trip, trip_tri)
}

/// Right-hand side weights per corner: `b_i += L_t · w_t,i` with
/// `w_t,i = Σ_(j≠i) cot θ_ij (x_i - x_j)` (Liu et al. 2008, eq. 6).
fn corner_weights(frames: &TriangleFrames) -> Vec<[[f64; 2]; 3]> {
    (0..frames.len())
        .into_par_iter()
        .with_min_len(PAR_CHUNK)
        .map(|t| {
            let x = frames.local[t];
            let c = frames.cot[t];
            let mut w = [[0.0; 2]; 3];
            for k in 0..3 {
                let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
                // edge (k, k1) is opposite corner k2, edge (k, k2) opposite corner k1
                for d in 0..2 {
                    w[k][d] = c[k2] * (x[k][d] - x[k1][d]) + c[k1] * (x[k][d] - x[k2][d]);
                }
            }
            w
        })
        .collect()
}

/// `∇E` on the free vertices (row `row_of[v]`, `u32::MAX` for a fixed vertex), written to
/// `out`: at vertex i, `Σ_t Σ_j cot θ_ij ((u_i - u_j) - L_t (x_i - x_j))` (Liu et al. 2008,
/// eq. 6). The two halves of the triangle list are scattered into the two `halves` buffers
/// (one per vertex, resized here) on two threads, then summed; the split does not depend on
/// the thread count, so neither does the result (camelhead, timed inside the loop: 300 us for
/// the sequential scatter, 220-330 for the halves on one thread, 170-250 on two; in a later
/// session's whole runs, 240-250 on two threads against 220-310 on one, no gain measurable
/// that day, see docs/arap.md). A parallel
/// gather per vertex over its triangles measured slower (camelhead plain iteration 2.9 -> 3.5
/// ms), its reads of the UVs being scattered.
fn gradient_into(
    frames: &TriangleFrames,
    corner_w: &[[[f64; 2]; 3]],
    targets: &[Similarity],
    uv: &[[f64; 2]],
    row_of: &[u32],
    halves: &mut [Vec<[f64; 2]>; 2],
    out: &mut Mat<f64>,
) {
    let m = frames.len();
    let scatter = |range: std::ops::Range<usize>, acc: &mut Vec<[f64; 2]>| {
        acc.clear();
        acc.resize(uv.len(), [0.0; 2]);
        for t in range {
            let [a, b] = targets[t];
            let tri = frames.triangles[t];
            let c = frames.cot[t];
            for k in 0..3 {
                let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
                let (u, u1, u2) = (
                    uv[tri[k] as usize],
                    uv[tri[k1] as usize],
                    uv[tri[k2] as usize],
                );
                let w = corner_w[t][k];
                let lw = [a * w[0] - b * w[1], b * w[0] + a * w[1]];
                let g = &mut acc[tri[k] as usize];
                for dim in 0..2 {
                    g[dim] += c[k2] * (u[dim] - u1[dim]) + c[k1] * (u[dim] - u2[dim]) - lw[dim];
                }
            }
        }
    };
    let [h0, h1] = halves;
    rayon::join(|| scatter(0..m / 2, h0), || scatter(m / 2..m, h1));
    for (v, &fi) in row_of.iter().enumerate() {
        if fi != u32::MAX {
            for dim in 0..2 {
                out[(fi as usize, dim)] = h0[v][dim] + h1[v][dim];
            }
        }
    }
}

/// The triangles of each vertex, in compressed rows (`start`, `triangle`).
fn vertex_triangles(n: usize, triangles: &[[u32; 3]]) -> (Vec<usize>, Vec<u32>) {
    let mut start = vec![0usize; n + 1];
    for tri in triangles {
        for &v in tri {
            start[v as usize + 1] += 1;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut next = start.clone();
    let mut list = vec![0u32; start[n]];
    for (t, tri) in triangles.iter().enumerate() {
        for &v in tri {
            list[next[v as usize]] = t as u32;
            next[v as usize] += 1;
        }
    }
    (start, list)
}

/// Local stiffened re-solve of a blocked step: on the vertices within `rings` rings of the
/// triangles that would reach their area floor before `best_step`, replaces `d` by the
/// minimizer of the global step's model `g·δ + ½ δᵀ Δ_W δ` (stiffened weights `Δ_W`) with `δ`
/// held at `d` everywhere else, a small Dirichlet problem factored on the spot, its vertices
/// numbered in the global factor's elimination order (`row_of`: a vertex's row in it, also
/// its row in `gradient`; `u32::MAX` when fixed), which fills no more than the global factor
/// does there and spares computing an ordering. The blocking
/// triangles then move almost rigidly with their surroundings instead of cutting the step for
/// the whole mesh, without refactoring the global Laplacian. Returns the number of vertices
/// re-solved; `touched` receives the triangles whose direction changed. `adjacency` lists each
/// vertex's triangles (compressed rows); `mark` and `seen` are scratch (all `u32::MAX` and
/// `false` on entry and exit).
#[allow(clippy::too_many_arguments)]
fn local_resolve(
    frames: &TriangleFrames,
    weights: &[f64],
    limits: &[f64],
    best_step: f64,
    rings: usize,
    row_of: &[u32],
    gradient: &Mat<f64>,
    adjacency: &(Vec<usize>, Vec<u32>),
    mark: &mut [u32],
    seen: &mut [bool],
    touched: &mut Vec<u32>,
    d: &mut [[f64; 2]],
) -> Result<usize, String> {
    let tris = &frames.triangles;
    let (vt_start, vt) = (&adjacency.0, &adjacency.1);
    // seed (ring 0): free vertices of the blocking triangles; `mark` holds the ring while
    // growing, then the local index
    let mut region: Vec<u32> = Vec::new();
    for (tri, &lim) in tris.iter().zip(limits) {
        if STEP_SAFETY * lim < best_step {
            for &v in tri {
                if mark[v as usize] == u32::MAX && row_of[v as usize] != u32::MAX {
                    mark[v as usize] = 0;
                    region.push(v);
                }
            }
        }
    }
    let mut ring_start = 0;
    for ring in 0..rings as u32 {
        let ring_end = region.len();
        for k in ring_start..ring_end {
            let v = region[k] as usize;
            for &t in &vt[vt_start[v]..vt_start[v + 1]] {
                for &u in &tris[t as usize] {
                    if mark[u as usize] == u32::MAX && row_of[u as usize] != u32::MAX {
                        mark[u as usize] = ring + 1;
                        region.push(u);
                    }
                }
            }
        }
        ring_start = ring_end;
    }
    // numbered in the global factor's elimination order, a fill-reducing order for the region
    region.sort_unstable_by_key(|&v| row_of[v as usize]);
    for (k, &v) in region.iter().enumerate() {
        mark[v as usize] = k as u32;
    }
    let r = region.len();
    touched.clear();
    let result = (|| {
        if r == 0 {
            return Err("no free vertex to re-solve".to_string());
        }
        // Δ_W restricted to the region (upper triangle in compressed columns, assembled column
        // by column in the region's order) and -g - Δ_W,RO d_O
        let mut rhs = Mat::<f64>::zeros(r, 2);
        let mut col_ptr = Vec::with_capacity(r + 1);
        let mut rows: Vec<usize> = Vec::with_capacity(5 * r);
        let mut vals: Vec<f64> = Vec::with_capacity(5 * r);
        let mut column: Vec<(usize, f64)> = Vec::new();
        col_ptr.push(0);
        for (k, &v) in region.iter().enumerate() {
            let f = row_of[v as usize] as usize;
            let (mut r0, mut r1) = (-gradient[(f, 0)], -gradient[(f, 1)]);
            let mut diag = 0.0;
            column.clear();
            for &t in &vt[vt_start[v as usize]..vt_start[v as usize + 1]] {
                if !seen[t as usize] {
                    seen[t as usize] = true;
                    touched.push(t);
                }
                let (t, tri) = (t as usize, tris[t as usize]);
                let c = (0..3).find(|&c| tri[c] == v).unwrap_or(0);
                // edge (v, tri[c+1]) is opposite corner c+2, edge (v, tri[c+2]) opposite c+1
                for (u, opposite) in [
                    (tri[(c + 1) % 3], (c + 2) % 3),
                    (tri[(c + 2) % 3], (c + 1) % 3),
                ] {
                    let w = frames.cot[t][opposite] * weights[t];
                    diag += w;
                    let ru = mark[u as usize];
                    if ru == u32::MAX {
                        // neighbour outside: held at d (zero when pinned)
                        r0 += w * d[u as usize][0];
                        r1 += w * d[u as usize][1];
                    } else if (ru as usize) < k {
                        match column.iter_mut().find(|e| e.0 == ru as usize) {
                            Some(e) => e.1 -= w,
                            None => column.push((ru as usize, -w)),
                        }
                    }
                }
            }
            rhs[(k, 0)] = r0;
            rhs[(k, 1)] = r1;
            column.sort_unstable_by_key(|e| e.0);
            for &(row, val) in &column {
                rows.push(row);
                vals.push(val);
            }
            rows.push(k);
            vals.push(diag);
            col_ptr.push(rows.len());
        }
        let upper = SparseColMat::new(
            SymbolicSparseColMat::new_checked(r, r, col_ptr, None, rows),
            vals,
        );
        let f = SpdFactor::from_upper_in_order(upper, Par::Seq)?;
        f.solve_in_place(rhs.as_mut());
        if !rhs.col_iter().all(|c| c.iter().all(|x| x.is_finite())) {
            return Err("non-finite local solution".to_string());
        }
        for (k, &v) in region.iter().enumerate() {
            d[v as usize] = [rhs[(k, 0)], rhs[(k, 1)]];
        }
        Ok(r)
    })();
    for &v in &region {
        mark[v as usize] = u32::MAX;
    }
    for &t in touched.iter() {
        seen[t as usize] = false;
    }
    result
}

/// Multiplies by `REWEIGHT_FACTOR` the weight of every triangle that would flip before
/// `best_step` (`limits < best_step`); returns how many changed. Between refactorizations a
/// triangle that keeps blocking keeps stiffening, so that it is frozen once the factor is
/// refreshed.
fn reweight(limits: &[f64], best_step: f64, weights: &mut [f64]) -> usize {
    let mut changed = 0;
    for (w, &lim) in weights.iter_mut().zip(limits) {
        if lim < best_step && *w < MAX_WEIGHT {
            *w = (*w * REWEIGHT_FACTOR).min(MAX_WEIGHT);
            changed += 1;
        }
    }
    changed
}

/// Marks one vertex per connected component (the `pin` in its component, otherwise the
/// component's lowest vertex) and every vertex that no triangle uses.
fn fixed_vertices(n: usize, triangles: &[[u32; 3]], pin: Option<usize>) -> Vec<bool> {
    let (comp, ncomp) = component_of(n, triangles);
    let mut fixed: Vec<bool> = comp.iter().map(|&c| c == u32::MAX).collect();
    let mut has_pin = vec![false; ncomp];
    if let Some(p) = pin.filter(|&p| comp[p] != u32::MAX) {
        has_pin[comp[p] as usize] = true;
        fixed[p] = true;
    }
    for v in 0..n {
        let c = comp[v];
        if c != u32::MAX && !has_pin[c as usize] {
            has_pin[c as usize] = true;
            fixed[v] = true;
        }
    }
    fixed
}

fn declare_common(b: &mut NodeBuilder) {
    b.add_input::<Mesh>("mesh")
        .doc("Mesh to flatten (triangulated if needed).");
    b.add_input::<Mesh>("init").optional().doc(
        "Mesh carrying the initial UVs (per vertex). Default: Tutte on a circle with mean-value weights, holes filled.",
    );
    b.add_input::<i64>("iterations")
        .default(100i64)
        .range(0.0, 100000.0)
        .doc("Maximum number of local/global iterations.");
    b.add_input::<f64>("tolerance")
        .default(1e-6)
        .range(0.0, 1.0)
        .doc("Stop when an iteration lowers the energy by less than this fraction.");
    b.add_input::<bool>("injective")
        .default(true)
        .doc("Fold-free: never accept a step that flips a triangle.");
    b.add_input::<i64>("pin")
        .default(-1i64)
        .min(-1.0)
        .doc("Vertex kept at its initial UV; -1: the first vertex.");
    b.add_input::<bool>("normalize").default(true).doc(
        "Scale and move the UVs into [0,1]² (same scale on both axes); `flat` keeps the true size.",
    );
    b.add_output::<Mesh>("mesh")
        .doc("The input mesh with per-vertex UVs.");
    b.add_output::<Mesh>("flat")
        .doc("The flattened mesh (UV, 0), at the 3-D scale.");
    b.add_output::<Table>("log").doc(
        "Per iteration: energy, flips, elapsed_ms, step, blocked (1: cut short to avoid a flip), refactors (numeric refactorizations after stiffening triangles); meta: stop_reason, flips, energy, reweighted, refactors.",
    );
}

fn declare_arap(b: &mut NodeBuilder) {
    b.doc("ARAP parameterization (Liu et al. 2008 local/global), fold-free by default.")
        .category("param");
    declare_common(b);
}

fn declare_hybrid(b: &mut NodeBuilder) {
    b.doc("Hybrid ARAP/ASAP parameterization (Liu et al. 2008 §4.3): lambda blends similarity (0) and rotation (large).")
        .category("param");
    declare_common(b);
    b.add_input::<f64>("lambda")
        .default(1.0)
        .range(0.0, 1e9)
        .doc("Weight of the scale term: 0 is ASAP, large values tend to ARAP.");
}

fn execute_with(ctx: &mut ExecContext, lambda: Option<f64>) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let init: Option<Arc<Mesh>> = ctx.input_opt("init")?;
    let iterations: i64 = ctx.input("iterations")?;
    let tolerance: f64 = ctx.input("tolerance")?;
    let injective: bool = ctx.input("injective")?;
    let pin: i64 = ctx.input("pin")?;
    let normalize: bool = ctx.input("normalize")?;
    let tri_mesh = mesh.triangulated();
    let triangles = tri_mesh
        .triangles()
        .ok_or_else(|| NodeError::invalid("mesh", "could not triangulate the mesh"))?;
    let (uv0, init_note) = init_uvs(&tri_mesh, init.as_deref())?;
    ctx.log(init_note);
    let opts = ArapOptions {
        iterations: iterations.max(0) as usize,
        tolerance,
        injective,
        pin: (pin >= 0).then_some(pin as usize),
        lambda,
        ..Default::default()
    };
    let res = arap_parameterize(&tri_mesh.positions, &triangles, &uv0, &opts)?;
    let mut table = Table::with_columns(&[
        "iteration",
        "energy",
        "flips",
        "elapsed_ms",
        "step",
        "blocked",
        "refactors",
    ]);
    for r in &res.log {
        table.push_row(&[
            r.iteration as f64,
            r.energy,
            r.flips as f64,
            r.elapsed_ms,
            r.step,
            f64::from(u8::from(r.blocked)),
            r.refactors as f64,
        ]);
    }
    table
        .meta
        .insert("stop_reason".into(), res.stop_reason.as_str().into());
    table.meta.insert("flips".into(), res.flips.to_string());
    table
        .meta
        .insert("reweighted".into(), res.reweighted.to_string());
    table
        .meta
        .insert("refactors".into(), res.refactors.to_string());
    if !res.stop_detail.is_empty() {
        table
            .meta
            .insert("stop_detail".into(), res.stop_detail.clone());
        ctx.log(format!("stopped: {}", res.stop_detail));
    }
    table
        .meta
        .insert("energy".into(), format!("{:.6e}", res.energy));
    ctx.log(format!(
        "{} iterations, energy {:.4e} -> {:.4e}, {} flipped triangles, stopped: {}",
        res.log.len() - 1,
        res.log[0].energy,
        res.energy,
        res.flips,
        res.stop_reason.as_str()
    ));
    let (out, flat) = uv_outputs(&mesh, &tri_mesh, &res.uv, normalize);
    ctx.set_output("mesh", out);
    ctx.set_output("flat", flat);
    ctx.set_output("log", table);
    Ok(())
}

fn execute_arap(ctx: &mut ExecContext) -> Result<(), NodeError> {
    execute_with(ctx, None)
}

fn execute_hybrid(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let lambda: f64 = ctx.input("lambda")?;
    execute_with(ctx, Some(lambda))
}

/// Registers `arap` and `arap_hybrid`.
pub fn register(r: &mut Registry) {
    r.add("arap", declare_arap, execute_arap);
    r.add("arap_hybrid", declare_hybrid, execute_hybrid);
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A wavy-free planar disk: a triangulated regular grid in the plane z = 0.
    pub(crate) fn planar_grid(k: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let mut p = Vec::new();
        for j in 0..=k {
            for i in 0..=k {
                let (x, y) = (i as f64 / k as f64, j as f64 / k as f64);
                // irregular but planar: shift interior points a little
                let s = if i > 0 && i < k && j > 0 && j < k {
                    0.2 / k as f64
                } else {
                    0.0
                };
                p.push([x + s * ((i * 7 + j * 3) % 5) as f64 / 5.0, y, 0.0]);
            }
        }
        let id = |i: usize, j: usize| (j * (k + 1) + i) as u32;
        let mut t = Vec::new();
        for j in 0..k {
            for i in 0..k {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        (p, t)
    }

    /// A pass over a few changed triangles gives exactly what a full pass over the new
    /// direction gives (same block sums, same smallest limit), on a mesh of several blocks.
    #[test]
    fn partial_directional_pass_matches_a_full_pass() {
        let (p, tris) = planar_grid(40); // 3200 triangles: 13 blocks, 2 parallel chunks
        let frames = TriangleFrames::new(&p, &tris).unwrap();
        let (n, m) = (p.len(), frames.len());
        let wobble = |v: usize, s: f64| [(v as f64 * s).sin(), (v as f64 * s * 1.3).cos()];
        let uv: Vec<[f64; 2]> = p.iter().map(|q| [q[0], q[1]]).collect();
        let mut targets = vec![[1.0, 0.0]; m];
        evaluate(&frames, &uv, None, &mut targets);
        let mut d: Vec<[f64; 2]> = (0..n).map(|v| wobble(v, 0.37).map(|x| 0.01 * x)).collect();
        let new_limits = |m: usize| StepLimits {
            floor2: vec![[1e-6, 1e-9]; m],
            limits: vec![f64::INFINITY; m],
            terms: vec![[0.0; 2]; m],
            blocks: vec![BlockSum::default(); m.div_ceil(SUM_BLOCK)],
            dirty: vec![false; m.div_ceil(SUM_BLOCK)],
        };
        let mut partial = new_limits(m);
        partial.directional(&frames, &uv, &d, &targets, None);
        // change the direction on a band of vertices, large enough to set the max step
        let moved: Vec<usize> = (0..n).filter(|v| (600..700).contains(v)).collect();
        for &v in &moved {
            d[v] = wobble(v, 1.1).map(|x| 0.2 * x);
        }
        let touched: Vec<u32> = (0..m as u32)
            .filter(|&t| {
                tris[t as usize]
                    .iter()
                    .any(|&v| moved.contains(&(v as usize)))
            })
            .collect();
        let a = partial.directional(&frames, &uv, &d, &targets, Some(&touched));
        let b = new_limits(m).directional(&frames, &uv, &d, &targets, None);
        assert!(
            a.max_step.is_finite() && a.max_step < 10.0,
            "{}",
            a.max_step
        );
        assert_eq!(
            (a.slope, a.best_step, a.max_step, a.squeezed),
            (b.slope, b.best_step, b.max_step, b.squeezed)
        );
        assert!(partial.dirty.iter().all(|&x| !x));
    }

    /// `local_resolve` against the global step it refines: with unit weights the global step
    /// already minimizes the model on any region (so nothing changes), and with stiffened
    /// blocking triangles those stop deforming (`J(δ) → 0`: they only translate).
    #[test]
    fn local_resolve_keeps_the_global_step_and_freezes_stiff_triangles() {
        let (p, t) = planar_grid(12);
        let uv0: Vec<[f64; 2]> = p
            .iter()
            .map(|q| {
                [
                    1.3 * q[0] + 0.2 * q[1] * q[1],
                    0.8 * q[1] + 0.1 * q[0] * q[1],
                ]
            })
            .collect();
        let frames = TriangleFrames::new(&p, &t).unwrap();
        let (n, m) = (p.len(), frames.len());
        let fixed = fixed_vertices(n, &frames.triangles, None);
        let mut free_index = vec![u32::MAX; n];
        let mut free_vertices = Vec::new();
        for v in 0..n {
            if !fixed[v] {
                free_index[v] = free_vertices.len() as u32;
                free_vertices.push(v);
            }
        }
        let (trip, _) = laplacian_triplets(&frames, &free_index);
        let factor = SpdFactor::new(free_vertices.len(), &trip, Par::Seq).unwrap();
        // rows in the factor's elimination order, as `iterate` keeps them
        let (row_of, row_vertex) = elimination_rows(&factor, &free_index);
        let mut targets = vec![[1.0, 0.0]; m];
        evaluate(&frames, &uv0, None, &mut targets);
        let mut g = Mat::<f64>::zeros(free_vertices.len(), 2);
        gradient_into(
            &frames,
            &corner_weights(&frames),
            &targets,
            &uv0,
            &row_of,
            &mut [Vec::new(), Vec::new()],
            &mut g,
        );
        let mut rhs = g.clone();
        let mut d = vec![[0.0; 2]; n];
        descent_direction(&factor, &g, &mut rhs, &row_vertex, &mut d);
        // the same direction as a solve in the free vertices' own order
        let mut g_free = Mat::<f64>::zeros(free_vertices.len(), 2);
        for (f, &v) in free_vertices.iter().enumerate() {
            for c in 0..2 {
                g_free[(f, c)] = -g[(row_of[v] as usize, c)];
            }
        }
        factor.solve_in_place(g_free.as_mut());
        for (f, &v) in free_vertices.iter().enumerate() {
            for c in 0..2 {
                assert!((g_free[(f, c)] - d[v][c]).abs() <= 1e-12 * (1.0 + d[v][c].abs()));
            }
        }
        // four triangles near the middle "block" the step
        let centre = |t: usize| {
            let c = frames.triangles[t].map(|v| p[v as usize]);
            [
                (c[0][0] + c[1][0] + c[2][0]) / 3.0,
                (c[0][1] + c[1][1] + c[2][1]) / 3.0,
            ]
        };
        let blocked: Vec<usize> = (0..m)
            .filter(|&t| {
                let c = centre(t);
                (c[0] - 0.5).abs() < 0.09 && (c[1] - 0.5).abs() < 0.05
            })
            .take(4)
            .collect();
        assert_eq!(blocked.len(), 4);
        let mut limits = vec![f64::INFINITY; m];
        for &b in &blocked {
            limits[b] = 0.1;
        }
        let adjacency = vertex_triangles(n, &frames.triangles);
        let (mut mark, mut seen, mut touched) = (vec![u32::MAX; n], vec![false; m], Vec::new());
        let dmax = d
            .iter()
            .map(|x| x[0].abs().max(x[1].abs()))
            .fold(0.0, f64::max);
        assert!(dmax > 1e-3);

        let mut resolve = |w: &[f64], d: &mut [[f64; 2]]| {
            let r = local_resolve(
                &frames,
                w,
                &limits,
                1.0,
                2,
                &row_of,
                &g,
                &adjacency,
                &mut mark,
                &mut seen,
                &mut touched,
                d,
            )
            .unwrap();
            (r, touched.len())
        };
        let mut d1 = d.clone();
        let (r, changed) = resolve(&vec![1.0; m], &mut d1);
        assert!(r > 6 && r < n / 2, "region of {r} vertices");
        assert!(changed > 0);
        for (a, b) in d.iter().zip(&d1) {
            assert!((a[0] - b[0]).abs() + (a[1] - b[1]).abs() < 1e-9 * dmax);
        }

        let mut w = vec![1.0; m];
        for &b in &blocked {
            w[b] = 1e8;
        }
        let mut d2 = d.clone();
        resolve(&w, &mut d2);
        assert!(mark.iter().all(|&x| x == u32::MAX) && seen.iter().all(|&x| !x));
        let norm = |j: [[f64; 2]; 2]| {
            (j[0][0].powi(2) + j[0][1].powi(2) + j[1][0].powi(2) + j[1][1].powi(2)).sqrt()
        };
        for &b in &blocked {
            let (before, after) = (norm(frames.jacobian(b, &d)), norm(frames.jacobian(b, &d2)));
            assert!(before > 1e-3, "triangle {b} barely deforms: {before}");
            assert!(
                after < 1e-4 * before,
                "triangle {b}: |J(d)| {before} -> {after}"
            );
        }
        // outside the region the global step is kept
        let region: Vec<bool> = (0..n).map(|v| d2[v] != d[v]).collect();
        assert!(region.iter().filter(|&&x| x).count() <= r);
    }

    #[test]
    fn planar_mesh_comes_back_rigidly() {
        let (p, t) = planar_grid(8);
        // start from an anisotropic, rotated, fold-free squash of the true layout
        let init: Vec<[f64; 2]> = p
            .iter()
            .map(|q| {
                [
                    0.3 * q[0] + 0.1 * q[1],
                    -0.2 * q[0] + 1.7 * q[1] + 0.05 * q[0] * q[0],
                ]
            })
            .collect();
        for injective in [false, true] {
            let opts = ArapOptions {
                iterations: 500,
                tolerance: 0.0,
                injective,
                ..Default::default()
            };
            let r = arap_parameterize(&p, &t, &init, &opts).unwrap();
            assert!(r.energy < 1e-16, "energy {}", r.energy);
            // all pairwise distances preserved: a rigid motion
            let d =
                |a: [f64; 2], b: [f64; 2]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
            let d3 =
                |a: [f64; 3], b: [f64; 3]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
            for i in (0..p.len()).step_by(7) {
                for j in (0..p.len()).step_by(5) {
                    assert!((d(r.uv[i], r.uv[j]) - d3(p[i], p[j])).abs() < 1e-7);
                }
            }
            assert_eq!(r.flips, 0);
        }
    }

    #[test]
    fn clockwise_start_is_mirrored_and_restored() {
        let (p, t) = planar_grid(4);
        let init: Vec<[f64; 2]> = p.iter().map(|q| [q[0] * 0.5, -q[1]]).collect();
        let r = arap_parameterize(&p, &t, &init, &ArapOptions::default()).unwrap();
        let f = TriangleFrames::new(&p, &t).unwrap();
        // still clockwise, and rigid
        assert!((0..t.len()).all(|k| f.signed_area2(k, &r.uv) < 0.0));
        assert!(r.energy < 1e-10);
    }

    #[test]
    fn refuses_folded_start_in_fold_free_mode() {
        let (p, t) = planar_grid(3);
        let mut init: Vec<[f64; 2]> = p.iter().map(|q| [q[0], q[1]]).collect();
        init[5] = [2.0, 2.0];
        let e = arap_parameterize(&p, &t, &init, &ArapOptions::default()).unwrap_err();
        assert_eq!(e.kind, ErrorKind::Folded);
        let opts = ArapOptions {
            injective: false,
            ..Default::default()
        };
        assert!(arap_parameterize(&p, &t, &init, &opts).is_ok());
        let bad = ArapOptions {
            pin: Some(1000),
            ..Default::default()
        };
        assert!(arap_parameterize(&p, &t, &init, &bad).is_err());
    }

    #[test]
    fn hybrid_on_planar_mesh_reaches_zero_energy() {
        let (p, t) = planar_grid(5);
        let init: Vec<[f64; 2]> = p.iter().map(|q| [0.5 * q[0], 0.7 * q[1]]).collect();
        let opts = ArapOptions {
            iterations: 500,
            tolerance: 0.0,
            lambda: Some(2.0),
            ..Default::default()
        };
        let r = arap_parameterize(&p, &t, &init, &opts).unwrap();
        assert!(r.energy < 1e-14, "{}", r.energy);
    }
}
