//! What the local/global iteration measures and returns: the local step over every triangle
//! with the energy and flips it finds (`evaluate`), the convergence log's rows
//! (`ArapIteration`) and the result (`ArapResult`). Below both the loop (`solver`) and its
//! entry points (`local_global`).

use super::frames::{local_step, Similarity, TriangleFrames, PAR_CHUNK};
use super::StopReason;
use rayon::prelude::*;

/// The columns of the convergence log as the `arap` node's table and the benchmark's CSV
/// write it, one per field of `ArapIteration`.
pub const LOG_COLUMNS: [&str; 7] = [
    "iteration",
    "energy",
    "flips",
    "elapsed_ms",
    "step",
    "blocked",
    "refactors",
];

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

/// Local step for every triangle at `uv` (targets written to `targets`), returning the
/// area-weighted energy sum and the number of triangles with `det J <= 0`.
pub(super) fn evaluate(
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
