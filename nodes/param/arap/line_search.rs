//! The fold-free line search's pass over the triangles (Smith & Schaefer 2015, §4): along a
//! search direction, the slope and curvature of the energy with the targets held fixed, and
//! the largest step that keeps every triangle's UV area above its floor. Sums are taken per
//! fixed block of triangles so that results are bit-identical whatever rayon's scheduling,
//! and a pass over a few changed triangles re-sums only their blocks.

use super::frames::{Similarity, TriangleFrames, PAR_CHUNK};
use super::injective::{area_coefficients, smallest_positive_root};
use super::options::{AREA_FLOOR, AREA_MARGIN};
use cgnodes_api::types::vec3::cross2;
use rayon::prelude::*;

/// Per triangle, twice the UV area of its margin and of its hard floor (see `AREA_MARGIN`
/// and `AREA_FLOOR`), from the start `uv` scaled to the 3-D area.
pub(super) fn area_floors(frames: &TriangleFrames, uv: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let m = frames.len();
    let a2: Vec<f64> = (0..m).map(|t| frames.signed_area2(t, uv)).collect();
    let ratio = a2.iter().sum::<f64>() / (2.0 * frames.total_area);
    a2.iter()
        .zip(&frames.area)
        .map(|(&a2, &area)| {
            let a3 = 2.0 * area * ratio;
            [AREA_MARGIN * a3, (AREA_FLOOR * a3).min(0.5 * a2)]
        })
        .collect()
}

/// What the energy does along a direction `δ` with the targets held fixed.
pub(super) struct Directional {
    /// `dE/ds` at `s = 0`: `Σ 2 A <J(uv) - L, J(δ)>`.
    pub slope: f64,
    /// Minimizer of the quadratic `E + s·slope + s²·Σ A |J(δ)|²` (1 for the global step).
    pub best_step: f64,
    /// Largest step keeping every triangle's orientation.
    pub max_step: f64,
    /// Whether the triangle that sets `max_step` is already below its area margin (it is
    /// being squeezed towards its hard floor: stiffening it cannot wait).
    pub squeezed: bool,
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
/// re-sums only their blocks (a full re-sum costs as much as a local re-solve's pass).
pub(super) struct StepLimits {
    /// Twice the UV area of the margin and of the hard floor (see `AREA_MARGIN`).
    floor2: Vec<[f64; 2]>,
    /// The step at which the triangle's UV area would reach its floor.
    pub limits: Vec<f64>,
    /// `[2 A <J(uv) - L, J(δ)>, A |J(δ)|²]` (see `line_terms`).
    terms: Vec<[f64; 2]>,
    /// Sums per block of triangles.
    blocks: Vec<BlockSum>,
    /// Scratch: blocks with a changed triangle (all `false` between calls).
    dirty: Vec<bool>,
}

impl StepLimits {
    /// No pass yet, with each triangle's area floors (`area_floors`).
    pub fn new(floor2: Vec<[f64; 2]>) -> StepLimits {
        StepLimits {
            limits: vec![f64::INFINITY; floor2.len()],
            terms: vec![[0.0; 2]; floor2.len()],
            blocks: vec![BlockSum::default(); floor2.len().div_ceil(SUM_BLOCK)],
            dirty: vec![false; floor2.len().div_ceil(SUM_BLOCK)],
            floor2,
        }
    }

    /// One parallel pass over the triangles: slope and curvature of the targets' quadratic
    /// along `dir`, and each triangle's orientation limit: the step at which its UV area
    /// would drop to its floor, `max(hard, min(margin, half the current area))`. With
    /// `changed`, `dir` differs from the last call only on those triangles: only their
    /// terms are recomputed. Sums are taken per fixed block, blocks in order, so the
    /// result depends neither on rayon's scheduling nor on which triangles were recomputed.
    pub fn directional(
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

#[cfg(test)]
mod tests {
    use super::super::energy::evaluate;
    use super::super::local_global::tests::planar_grid;
    use super::*;

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
        let new_limits = |m: usize| StepLimits::new(vec![[1e-6, 1e-9]; m]);
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
}
