//! Geometric multigrid for the Poisson matrix of an arbitrary Ω (`system.rs`: 4 on the
//! diagonal, -1 per inside 4-neighbour, Dirichlet zero outside), used as the preconditioner
//! of conjugate gradients (MGCG, Tatebe 1993, "The multigrid preconditioned conjugate
//! gradient method", 6th Copper Mountain Conference).
//!
//! The hierarchy is vertex-centred on the pixel grid (Trottenberg, Oosterlee & Schüller,
//! "Multigrid", 2001, §2.3): coarse point `X` sits on fine point `2X`, prolongation `P` is
//! bilinear interpolation (weights 1, 1/2, 1/4; ibid. §2.3.3) and restriction its transpose
//! (full weighting times 4). The Dirichlet boundary of an irregular Ω is handled by the
//! Galerkin product (ibid. §2.3.2 and §7.7; Briggs, Henson & McCormick, "A Multigrid
//! Tutorial", 2nd ed., 2000, ch. 5): `P` is truncated to Ω's pixels, so a coarse point is
//! kept when its basis function touches Ω (the aggregation of the 3x3 fine block around it),
//! and `A_c = Pᵀ A P` is the exact energy of the truncated basis, a 9-point stencil on every
//! coarse level. A truncated basis can be linearly dependent (a lone pixel between four
//! coarse points), so `A_c` is only semi-definite; a correction along its null space is
//! `P e = 0` and changes nothing, and the coarsest level's sparse Cholesky factors `A_c` with
//! a relative diagonal shift of `COARSE_SHIFT` (its null-space part of the right-hand side is
//! zero up to rounding).
//!
//! Smoothing is Gauss-Seidel in four colours (the parities of x and y: points of one colour
//! never share a 9-point stencil, so a colour is updated all at once; on the 5-point fine
//! level this is red-black order). The pre-smoother runs the colours forwards and the
//! post-smoother backwards, so the V-cycle is a symmetric operator, as conjugate gradients
//! needs (Tatebe 1993, §2).
//!
//! Vectors live on the padded bounding box of each level (zero outside Ω), stored by colour
//! and channel (`field.rs`): every kernel is a flat loop over contiguous arrays, compiled to
//! packed SIMD arithmetic, in safe code. Conjugate gradients runs the three colour channels
//! in lockstep (one α and β each, one stopping test on their summed residual); the V-cycle
//! of each channel is a task of its own, the three in parallel, so that two threads meet
//! once per cycle instead of once per sweep.

use super::mask::MaskShape;
use super::PoissonError;
use cgnodes_linalg::SpdFactor;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Mat, MatMut, Par};
use rayon::prelude::*;
use std::sync::Mutex;

mod cg;
mod coarsen;
mod field;
mod grid;

use cg::*;
use coarsen::*;
use field::*;
use grid::*;

/// A level with at most this many unknowns is solved directly (sparse Cholesky). At 1024 the
/// course mask's coarsest level had 999 unknowns, whose factorization took 0.9 of the
/// hierarchy's 1.3 ms; at 256 it has 65 and the hierarchy takes 0.5-0.6 ms, with the same
/// iteration counts.
const COARSEST_MAX: usize = 256;

/// Relative diagonal shift of the coarsest matrix (see the module comment).
const COARSE_SHIFT: f64 = 1e-10;

/// Grid points from which a level's kernels run their pieces on several threads, also
/// inside each channel's V-cycle task (three tasks leave a thread idle for a third of the
/// cycle otherwise): the course's first paste (`course_first_paste_companion`, the node's
/// path) took 2.99-3.05 ms against 3.23-3.26 ms with the V-cycle's pieces on one thread.
const PAR_MIN: usize = 1 << 12;

/// Gauss-Seidel sweeps before and after the coarse correction (`Multigrid::sweeps`).
const SWEEPS: usize = 1;

/// A relative residual (`||b - A x|| / ||b||`, over all channels) below 1e-10 with margin for
/// the recurrence's drift (on the course mask the recurrence and the recomputed residual agreed
/// to three digits): the tolerance the solver's accuracy tests ask for, and the tightest a
/// paste needs (`poisson::DEFAULT_TOLERANCE` is the node's default).
pub const TOLERANCE: f64 = 8e-11;

/// Iterations after which conjugate gradients gives up (it needs about 10).
const MAX_ITERATIONS: usize = 200;

/// One colour channel's per-level vectors of a V-cycle (f32): each channel's V-cycle runs on
/// its own (three tasks on the threads, with one join per cycle instead of one per sweep).
#[derive(Default)]
struct Cycle {
    /// Per level: solution, right-hand side, and the residual before it is restricted.
    u: Vec<Grid>,
    b: Vec<Grid>,
    r: Vec<Grid>,
    /// Per level: coarse values laid out on this level's colour-0 grid, the restricted
    /// residual and the coarse correction in turn (`restrict_residual`, `prolong_add`).
    q: Vec<Vec<f32>>,
}

/// The V-cycle vectors of the three channels and the conjugate-gradient vectors (f64), kept
/// between solves.
struct Work {
    cyc: [Cycle; 3],
    /// Each level's operator in the colour layout (`Layout`).
    lay: Vec<Layout>,
    /// Conjugate gradients on the fine level: iterate, residual (f64), search direction
    /// (f32: `A p` is formed from it exactly in f64, so `x` and the residual stay consistent).
    x: Field<f64>,
    res: Field<f64>,
    p: Field<f32>,
    /// `Multigrid::id` of the hierarchy these fields are shaped for (zero outside its Ω).
    owner: u64,
}

/// The work buffers of the last finished solve, of whatever shape: the next solve reshapes
/// them instead of page-faulting fresh memory. With buffers of its own, a new shape's first
/// multigrid paste of the course mask spent 5.5-5.8 ms in its solve, the same shape's later
/// pastes 4.0-4.3 (docs/image.md).
static SPARE: Mutex<Option<Work>> = Mutex::new(None);

/// The solution of the last first solve of a shape, with the `Multigrid::id` of its
/// hierarchy: the warm start of that shape's second paste, unless another shape's first
/// solve came in between. A first solve writes here, into the memory of the previous one,
/// instead of into fresh pages of its own (on the course mask about 110 fewer page faults in
/// the bench's chain up to its first timed paste, counted with `perf stat`; some 0.15 ms at
/// this machine's 1.4 µs per fault): a shape pasted once, as in a one-off run, never pays for
/// a copy, and a shape's own copy (`Multigrid::last`) starts with its second solve.
static FIRST: Mutex<Option<(u64, Field<f64>)>> = Mutex::new(None);

/// Source of `Multigrid::id`.
static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// The multigrid hierarchy of one Ω: what the factorization cache keeps per mask shape.
pub struct Multigrid {
    levels: Vec<Level>,
    coarsest: Coarsest,
    /// Fine grid position `(y, x)` of unknown `k` (`MaskShape::inside` numbering).
    cells: Vec<[u32; 2]>,
    /// Identifies this hierarchy to the work buffers shaped for it (`Work::owner`).
    id: u64,
    /// Gauss-Seidel sweeps before and after each coarse correction.
    sweeps: usize,
    /// The last solution on the fine grid (one 3-channel group), a warm start for the next:
    /// kept here from the shape's second solve on (its first solve's is in `FIRST`).
    last: Mutex<Option<Field<f64>>>,
    /// Whether a solve has kept its solution (in `FIRST`; the later ones in `last`).
    kept: std::sync::atomic::AtomicBool,
}

/// What a multigrid solve did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    /// Conjugate-gradient iterations (one V-cycle each), the most of any 3-channel group.
    pub iterations: usize,
    /// Whether the previous solution was the starting guess.
    pub warm: bool,
    /// `||b - A x||²` at the end, summed over the channels, from the conjugate-gradient
    /// recurrence (in f64, `A p` formed exactly from the f32 direction, so it tracks the
    /// recomputed residual: tested to agree within 1 %).
    pub residual_sq: f64,
    /// `||b||²`, summed over the channels.
    pub rhs_sq: f64,
}

impl Stats {
    /// `||b - A x|| / ||b||` (`||b - A x||` when b = 0), from the recurrence.
    pub fn relative_residual(&self) -> f64 {
        if self.rhs_sq > 0.0 {
            (self.residual_sq / self.rhs_sq).sqrt()
        } else {
            self.residual_sq.sqrt()
        }
    }
}

/// Each channel's fine-level right-hand side.
fn b0(c: &mut [Cycle; 3]) -> [&mut Grid; 3] {
    c.each_mut().map(|c| &mut c.b[0])
}

/// Each channel's fine-level V-cycle result (the preconditioned residual `z`).
fn z0(c: &[Cycle; 3]) -> [&Grid; 3] {
    c.each_ref().map(|c| &c.u[0])
}

impl Multigrid {
    /// The hierarchy of `shape`'s Poisson matrix: coarse levels by Galerkin products until a
    /// level has at most `COARSEST_MAX` unknowns or cannot be coarsened, which is factored.
    pub fn new(shape: &MaskShape) -> Result<Multigrid, PoissonError> {
        let Some([x0, y0, x1, y1]) = shape.bbox() else {
            return Err(PoissonError::EmptyMask);
        };
        let (bw, bh) = ((x1 - x0 + 1) as usize, (y1 - y0 + 1) as usize);
        let (w, h) = ((bw + 2) | 1, (bh + 2) | 1);
        let mut inside = vec![false; w * h];
        let cells: Vec<[u32; 2]> = shape
            .inside
            .iter()
            .map(|&[x, y]| [y - y0 + 1, x - x0 + 1])
            .collect();
        for &[y, x] in &cells {
            inside[y as usize * w + x as usize] = true;
        }
        let mut levels = vec![Level::new(w, h, Op::Fine(inside), shape.len())];
        loop {
            let l = levels.last().expect("the fine level");
            if l.n <= COARSEST_MAX || l.w < 5 || l.h < 5 {
                break;
            }
            let c = galerkin(l);
            if c.n == 0 {
                break;
            }
            levels.push(c);
        }
        let coarsest = Coarsest::new(levels.last().expect("the fine level"))?;
        Ok(Multigrid {
            levels,
            coarsest,
            cells,
            id: NEXT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            sweeps: SWEEPS,
            last: Mutex::new(None),
            kept: std::sync::atomic::AtomicBool::new(false),
        })
    }

    /// The same hierarchy with `sweeps` smoothing sweeps before and after each coarse
    /// correction (at least 1; `SWEEPS` by default).
    pub fn with_sweeps(mut self, sweeps: usize) -> Multigrid {
        self.sweeps = sweeps.max(1);
        self
    }

    /// Number of levels (the finest included).
    pub fn depth(&self) -> usize {
        self.levels.len()
    }

    /// Unknowns of each level, finest first.
    pub fn unknowns(&self) -> Vec<usize> {
        self.levels.iter().map(|l| l.n).collect()
    }

    /// New work buffers shaped for this hierarchy.
    fn work(&self) -> Work {
        let mut wk = Work {
            cyc: Default::default(),
            lay: Vec::new(),
            x: Field::empty(),
            res: Field::empty(),
            p: Field::empty(),
            // no hierarchy's (ids start at 1)
            owner: 0,
        };
        self.shape_work(&mut wk);
        wk
    }

    /// Work buffers for a solve: the spare ones (`SPARE`), reshaped to this hierarchy unless
    /// they already are, else new ones.
    fn take_work(&self) -> Work {
        match SPARE.try_lock().ok().and_then(|mut s| s.take()) {
            Some(mut wk) => {
                self.shape_work(&mut wk);
                wk
            }
            None => self.work(),
        }
    }

    /// Reshapes `wk` (made for any hierarchy, or none) to this one's levels in the same
    /// memory where it fits, conjugate gradients' vectors zeroed, the V-cycle's left as they
    /// are (every kernel writes them before it reads them); nothing to do when `wk` was
    /// shaped for this hierarchy already.
    fn shape_work(&self, wk: &mut Work) {
        if wk.owner == self.id {
            return;
        }
        wk.lay = self.layouts(std::mem::take(&mut wk.lay));
        // every V-cycle vector is written in full before it is read: no clearing
        for cy in &mut wk.cyc {
            for v in [&mut cy.u, &mut cy.b, &mut cy.r] {
                v.resize_with(self.levels.len(), Grid::default);
                for (f, l) in v.iter_mut().zip(&self.levels) {
                    f.reshape(l.w, l.h);
                }
            }
            cy.q.resize_with(self.levels.len(), Vec::new);
            for (q, l) in cy.q.iter_mut().zip(&self.levels) {
                reshape(q, l.g.n2());
            }
        }
        let fine = &self.levels[0];
        wk.x.reset(fine.w, fine.h);
        wk.res.reset(fine.w, fine.h);
        wk.p.reset(fine.w, fine.h);
        wk.owner = self.id;
    }

    /// Every level's `Layout`, in the memory of `lay` where it fits (the coarsest level,
    /// solved directly, needs only its mask, for the restriction).
    fn layouts(&self, mut lay: Vec<Layout>) -> Vec<Layout> {
        lay.resize_with(self.levels.len(), Layout::default);
        for (l, (out, level)) in lay.iter_mut().zip(&self.levels).enumerate() {
            out.fill(level, l + 1 < self.levels.len());
        }
        lay
    }

    /// One symmetric V-cycle of one channel on level `l`: `u[l] ≈ A_l⁻¹ b[l]` from a zero
    /// start.
    fn vcycle(&self, l: usize, wk: &mut Cycle, lay: &[Layout]) {
        if l + 1 == self.levels.len() {
            self.coarsest.solve(&self.levels[l], &wk.b[l], &mut wk.u[l]);
            return;
        }
        let (level, coarse) = (&self.levels[l], &self.levels[l + 1]);
        for s in 0..self.sweeps {
            for c in COLOURS {
                smooth(level, &lay[l], &mut wk.u[l], &wk.b[l], c, s == 0);
            }
        }
        {
            let (lo, hi) = wk.b.split_at_mut(l + 1);
            restrict_residual(
                level,
                coarse,
                [&lay[l], &lay[l + 1]],
                &wk.u[l],
                Some(&lo[l]),
                true,
                &mut wk.r[l],
                &mut wk.q[l],
                &mut hi[0],
            );
        }
        self.vcycle(l + 1, wk, lay);
        {
            let (lo, hi) = wk.u.split_at_mut(l + 1);
            prolong_add(level, coarse, &lay[l], &hi[0], &mut wk.q[l], &mut lo[l]);
        }
        for _ in 0..self.sweeps {
            for c in COLOURS.into_iter().rev() {
                smooth(level, &lay[l], &mut wk.u[l], &wk.b[l], c, false);
            }
        }
    }

    /// `z = M r` into each channel's `u[0]`: one V-cycle on the fine level from a zero start
    /// (the preconditioner), with `r` already in `b[0]` (rounded to f32); the channels in
    /// parallel.
    fn precondition(&self, wk: &mut Work) {
        let ([a, b, c], lay) = (&mut wk.cyc, &wk.lay[..]);
        rayon::join(
            || self.vcycle(0, a, lay),
            || rayon::join(|| self.vcycle(0, b, lay), || self.vcycle(0, c, lay)),
        );
    }

    /// Solves `A X = B` in place, every column of `x` (in groups of three), by conjugate
    /// gradients preconditioned with one V-cycle per iteration, to a relative residual of
    /// `tolerance`. With `warm`, the previous solution starts the iteration when its residual
    /// is below `||b||` (a repeated paste of the same shape).
    pub fn solve_in_place(
        &self,
        x: MatMut<'_, f64>,
        warm: bool,
        tolerance: f64,
    ) -> Result<Stats, PoissonError> {
        let mut work = self.take_work();
        let stats = self.solve_with(&mut work, x, warm, tolerance)?;
        if let Ok(mut spare) = SPARE.try_lock() {
            *spare = Some(work);
        }
        Ok(stats)
    }

    /// `solve_in_place` in the work buffers `wk` (shaped for this hierarchy).
    fn solve_with(
        &self,
        wk: &mut Work,
        mut x: MatMut<'_, f64>,
        warm: bool,
        tolerance: f64,
    ) -> Result<Stats, PoissonError> {
        let mut stats = Stats::default();
        let ncols = x.ncols();
        for g in (0..ncols).step_by(3) {
            let cols = (ncols - g).min(3);
            // b into the residual field (outside Ω it stays zero)
            let geom = wk.res.g;
            for c in 0..cols {
                let col = x.as_ref().col(g + c);
                for (&[y, xx], v) in self.cells.iter().zip(col.iter()) {
                    let (k, i) = geom.at(y as usize, xx as usize);
                    wk.res.c[k][c][i] = *v;
                }
            }
            for c in cols..3 {
                for &[y, xx] in &self.cells {
                    let (k, i) = geom.at(y as usize, xx as usize);
                    wk.res.c[k][c][i] = 0.0;
                }
            }
            let reuse = warm && ncols == 3;
            let s = self.pcg(wk, reuse, tolerance)?;
            stats.iterations = stats.iterations.max(s.iterations);
            stats.warm |= s.warm;
            stats.residual_sq += s.residual_sq;
            stats.rhs_sq += s.rhs_sq;
            for c in 0..cols {
                for (&[y, xx], v) in self.cells.iter().zip(x.as_mut().col_mut(g + c).iter_mut()) {
                    let (k, i) = geom.at(y as usize, xx as usize);
                    *v = wk.x.c[k][c][i];
                }
            }
            if reuse {
                self.keep(&wk.x);
            }
        }
        Ok(stats)
    }

    /// Keeps `x`, this solve's solution, as the warm start of the shape's next solve: in
    /// `FIRST` after the shape's first solve, in `last` after the others.
    fn keep(&self, x: &Field<f64>) {
        if !self.kept.swap(true, std::sync::atomic::Ordering::Relaxed) {
            if let Ok(mut first) = FIRST.try_lock() {
                // into the previous first solve's memory (`Field::assign`)
                let (id, f) = first.get_or_insert_with(|| (self.id, Field::empty()));
                *id = self.id;
                f.assign(x);
            }
        } else if let Ok(mut last) = self.last.try_lock() {
            last.get_or_insert_with(Field::empty).assign(x);
        }
    }

    /// Preconditioned conjugate gradients, one per channel in lockstep, on `wk.res` = b;
    /// the solution in `wk.x`.
    fn pcg(&self, wk: &mut Work, warm: bool, tolerance: f64) -> Result<Stats, PoissonError> {
        let fine = &self.levels[0];
        let bn = norms(&wk.res);
        let flat = |p: P3| p.iter().sum::<f64>();
        let bnorm = bn.iter().sum::<f64>().sqrt();
        let mut stats = Stats {
            rhs_sq: bnorm * bnorm,
            ..Stats::default()
        };
        wk.x.fill_zero();
        if bnorm == 0.0 {
            return Ok(stats);
        }
        let goal = tolerance * bnorm;
        if warm {
            // the shape's own copy, else its first solve's if `FIRST` still holds it
            let (own, first) = (self.last.try_lock().ok(), FIRST.try_lock().ok());
            let last = own.as_deref().and_then(Option::as_ref).or_else(|| {
                let (id, f) = first.as_deref()?.as_ref()?;
                (*id == self.id).then_some(f)
            });
            if let Some(last) = last {
                // r = b - A x_last (in x for now), kept when it is smaller than b
                fine_residual(fine, &wk.lay[0], last, Some(&wk.res), &mut wk.x);
                if flat(norms(&wk.x)) < bnorm * bnorm {
                    std::mem::swap(&mut wk.res, &mut wk.x);
                    wk.x.assign(last);
                    stats.warm = true;
                } else {
                    wk.x.fill_zero();
                }
            }
        }
        let mut rn = flat(norms(&wk.res)).sqrt();
        stats.residual_sq = rn * rn;
        if rn <= goal {
            return Ok(stats);
        }
        // z = M r into u[0]; p = z
        to_f32(fine, &wk.res, b0(&mut wk.cyc));
        self.precondition(wk);
        next_direction(fine, &mut wk.p, z0(&wk.cyc), [0.0; 3]);
        let mut rz = z_dots(fine, z0(&wk.cyc), &wk.res, None).0;
        while rn > goal {
            if stats.iterations >= MAX_ITERATIONS {
                return Err(PoissonError::NoConvergence {
                    iterations: MAX_ITERATIONS,
                    residual: rn / bnorm,
                });
            }
            stats.iterations += 1;
            let pq = p_ap(fine, &wk.p);
            let alpha = std::array::from_fn::<f64, 3, _>(|c| {
                if pq[c] > 0.0 && rz[c] > 0.0 {
                    rz[c] / pq[c]
                } else {
                    0.0
                }
            });
            rn = flat(cg_update(
                fine,
                &wk.lay[0],
                &mut wk.x,
                &mut wk.res,
                &wk.p,
                b0(&mut wk.cyc),
                alpha,
            ))
            .sqrt();
            stats.residual_sq = rn * rn;
            if rn <= goal {
                break;
            }
            self.precondition(wk);
            // β of Polak and Ribière, zᵀ(r_new - r_old) / z_oldᵀ r_old with r_new - r_old =
            // -α A p: it tolerates the f32 V-cycle being not exactly the same symmetric operator
            // every time (flexible CG; Notay 2000, "Flexible conjugate gradients", SIAM J. Sci.
            // Comput. 22(4)), and equals Fletcher and Reeves' β when it is
            let (rz1, zq) = z_dots(fine, z0(&wk.cyc), &wk.res, Some(&wk.p));
            let beta = std::array::from_fn::<f64, 3, _>(|c| {
                if rz[c] > 0.0 {
                    (-alpha[c] * zq[c] / rz[c]).max(0.0)
                } else {
                    0.0
                }
            });
            rz = rz1;
            // p = z + β p
            next_direction(fine, &mut wk.p, z0(&wk.cyc), beta);
        }
        Ok(stats)
    }

    /// The convergence factor of the plain V-cycle iteration `u ← u + V(b - A u)` on `b`
    /// (one 3-channel group): the geometric mean of the residual reduction per cycle over
    /// `cycles` cycles. For tests and measurements.
    pub fn vcycle_rate(&self, b: faer::MatRef<'_, f64>, cycles: usize) -> f64 {
        let mut wk = self.work();
        let fine = &self.levels[0];
        wk.x.fill_zero();
        for (k, &[y, xx]) in self.cells.iter().enumerate() {
            let mut v = [0.0; 3];
            for (c, v) in v.iter_mut().enumerate().take(b.ncols()) {
                *v = b[(k, c)];
            }
            wk.x.set(y as usize, xx as usize, v);
        }
        let target = wk.x.clone();
        wk.x.fill_zero();
        let r0 = norms(&target).iter().sum::<f64>().sqrt();
        let mut r = r0;
        for _ in 0..cycles {
            fine_residual(fine, &wk.lay[0], &wk.x, Some(&target), &mut wk.res);
            to_f32(fine, &wk.res, b0(&mut wk.cyc));
            self.precondition(&mut wk);
            add_correction(&mut wk.x, z0(&wk.cyc));
            fine_residual(fine, &wk.lay[0], &wk.x, Some(&target), &mut wk.res);
            r = norms(&wk.res).iter().sum::<f64>().sqrt();
        }
        (r / r0).powf(1.0 / cycles as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::super::system;
    use super::*;

    /// A mask from a predicate on `w x h` pixels.
    fn mask(w: u32, h: u32, f: impl Fn(i64, i64) -> bool) -> MaskShape {
        let flags: Vec<bool> = (0..w * h)
            .map(|i| f((i % w) as i64, (i / w) as i64))
            .collect();
        MaskShape::from_flags(w, h, &flags)
    }

    fn disc(r: f64) -> MaskShape {
        let w = (2.0 * r) as u32 + 4;
        let c = w as f64 / 2.0;
        mask(w, w, |x, y| {
            let (dx, dy) = (x as f64 + 0.5 - c, y as f64 + 0.5 - c);
            dx * dx + dy * dy < r * r
        })
    }

    /// A deterministic right-hand side with smooth and rough parts.
    fn rhs(n: usize) -> Mat<f64> {
        let mut s = 12345u64;
        Mat::from_fn(n, 3, |i, c| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((i as f64) * 0.01 + c as f64).sin() + ((s >> 40) as f64 / (1u64 << 24) as f64 - 0.5)
        })
    }

    fn shapes() -> Vec<(&'static str, MaskShape)> {
        vec![
            ("disc", disc(40.0)),
            (
                "L-shape",
                mask(90, 80, |x, y| (x < 40 || y < 30) && x < 88 && y < 78),
            ),
            (
                "annulus (a hole)",
                mask(101, 101, |x, y| {
                    let d = ((x - 50) * (x - 50) + (y - 50) * (y - 50)) as f64;
                    d < 48.0 * 48.0 && d > 15.0 * 15.0
                }),
            ),
            (
                "two blobs",
                mask(120, 60, |x, y| {
                    let d1 = (x - 25) * (x - 25) + (y - 30) * (y - 30);
                    let d2 = (x - 90) * (x - 90) + (y - 28) * (y - 28);
                    d1 < 400 || d2 < 600
                }),
            ),
            (
                "one-pixel strips",
                // horizontal strips on odd and even rows, a vertical one, a diagonal staircase
                mask(130, 90, |x, y| {
                    (y % 7 == 3 && x > 2 && x < 120)
                        || (y % 11 == 0 && x > 10)
                        || (x == 64 && y > 0)
                        || (x == y && x < 80)
                }),
            ),
            (
                "touching the box (full box less a notch)",
                mask(70, 50, |x, y| !(x > 30 && y > 20 && x < 40)),
            ),
            ("single pixel", mask(3, 3, |x, y| x == 1 && y == 1)),
        ]
    }

    /// The residual a solve reports (`Stats::relative_residual`, from the recurrence) is the
    /// recomputed `||b - A x|| / ||b||` within 1 %, cold and warm, at the node's default
    /// tolerance and at the tight one.
    #[test]
    fn the_recurrence_residual_is_the_true_one() {
        for (name, shape) in shapes() {
            let b = rhs(shape.len());
            let mg = Multigrid::new(&shape).unwrap();
            for tol in [crate::poisson_blend::poisson::DEFAULT_TOLERANCE, TOLERANCE] {
                for warm in [false, true] {
                    let mut x = b.clone();
                    let stats = mg.solve_in_place(x.as_mut(), warm, tol).unwrap();
                    let r = system::residual_norm(&shape, x.as_ref(), b.as_ref()) / b.norm_l2();
                    let rec = stats.relative_residual();
                    assert!(rec <= tol, "{name} {tol:e}: {rec:e}");
                    assert!(
                        (rec - r).abs() <= 0.01 * r + 1e-15,
                        "{name} {tol:e} warm {warm}: recurrence {rec:e}, recomputed {r:e}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_shape_keeps_its_own_warm_start_from_its_second_solve() {
        let shape = disc(30.0);
        let b = rhs(shape.len());
        let mg = Multigrid::new(&shape).unwrap();
        let solve = || {
            let mut x = b.clone();
            mg.solve_in_place(x.as_mut(), true, TOLERANCE).unwrap()
        };
        let first = solve();
        assert!(!first.warm && first.iterations > 0);
        // the first solve's solution went to the shared slot, not to a copy of its own
        assert!(mg.last.lock().unwrap().is_none());
        // warm from the slot, unless another shape's first solve (a test running beside
        // this one) took it: then cold, as the first
        let second = solve();
        assert!(
            (second.warm && second.iterations == 0) || second.iterations == first.iterations,
            "{first:?} {second:?}"
        );
        assert!(mg.last.lock().unwrap().is_some());
        // from its own copy: the identical system needs no iteration
        let third = solve();
        assert!(third.warm && third.iterations == 0, "{third:?}");
    }

    #[test]
    fn matches_cholesky_on_irregular_masks() {
        for (name, shape) in shapes() {
            let n = shape.len();
            let b = rhs(n);
            let mut reference = b.clone();
            system::factor(&shape)
                .unwrap()
                .solve_in_place(reference.as_mut());
            let mg = Multigrid::new(&shape).unwrap();
            for warm in [false, true, true] {
                let mut x = b.clone();
                let stats = mg.solve_in_place(x.as_mut(), warm, TOLERANCE).unwrap();
                let r = system::residual_norm(&shape, x.as_ref(), b.as_ref()) / b.norm_l2();
                assert!(r <= 1e-10, "{name}: residual {r:.2e} ({stats:?})");
                let e = (&x - &reference).norm_l2() / reference.norm_l2();
                assert!(
                    e < 1e-9,
                    "{name}: relative difference {e:.2e} from Cholesky"
                );
            }
        }
    }

    #[test]
    fn work_buffers_of_another_shape_give_the_same_bits() {
        // the spare work buffers of any shape, reshaped (smaller, larger, fewer and more
        // levels), must solve exactly as freshly zeroed ones: nothing of the last shape left
        let all = shapes();
        for (i, (name, shape)) in all.iter().enumerate() {
            let mg = Multigrid::new(shape).unwrap();
            let b = rhs(shape.len());
            let mut fresh = mg.work();
            let mut x_fresh = b.clone();
            mg.solve_with(&mut fresh, x_fresh.as_mut(), false, TOLERANCE)
                .unwrap();
            // buffers dirtied by a solve of the previous shape
            let (_, other) = &all[(i + all.len() - 1) % all.len()];
            let mo = Multigrid::new(other).unwrap();
            let mut reused = mo.work();
            let mut y = rhs(other.len());
            mo.solve_with(&mut reused, y.as_mut(), false, TOLERANCE)
                .unwrap();
            mg.shape_work(&mut reused);
            let mut x_reused = b.clone();
            mg.solve_with(&mut reused, x_reused.as_mut(), false, TOLERANCE)
                .unwrap();
            assert!(
                x_fresh == x_reused,
                "{name}: reshaped buffers changed the solution"
            );
        }
    }

    #[test]
    fn every_piece_boundary_solves() {
        // L-shapes whose fine colour grids end just past a multiple of `PIECE` points, so
        // that the last piece lies wholly outside the kernels' span (a colour's border row),
        // and the sizes around them
        let mut hits = Vec::new();
        for bw in 40..140usize {
            for bh in [40usize, 57, 90] {
                let g = Geom::of((bw + 2) | 1, (bh + 2) | 1);
                let tail = g.n2() % PIECE;
                if tail > 0 && tail <= g.w2 + 1 {
                    hits.push((bw, bh));
                }
            }
        }
        assert!(!hits.is_empty());
        for &(bw, bh) in hits.iter().take(4) {
            for dw in [0, 1, 2] {
                let (w, h) = ((bw + dw) as i64, bh as i64);
                let shape = mask(w as u32 + 2, h as u32 + 2, |x, y| {
                    (1..=w).contains(&x) && (1..=h).contains(&y) && (x < w / 2 || y < h / 2)
                });
                let mg = Multigrid::new(&shape).unwrap();
                let b = rhs(shape.len());
                let mut x = b.clone();
                mg.solve_in_place(x.as_mut(), false, TOLERANCE).unwrap();
                let res = system::residual_norm(&shape, x.as_ref(), b.as_ref()) / b.norm_l2();
                assert!(res <= 1e-10, "{w} x {h}: {res:e}");
            }
        }
    }

    #[test]
    fn the_hierarchy_coarsens_and_solves_more_than_three_columns() {
        let shape = disc(60.0);
        let mg = Multigrid::new(&shape).unwrap();
        let u = mg.unknowns();
        assert!(mg.depth() >= 3, "{u:?}");
        assert!(
            u.windows(2).all(|p| p[1] < p[0]) && *u.last().unwrap() <= COARSEST_MAX,
            "{u:?}"
        );
        // five columns: a group of three and a group of two
        let b = Mat::from_fn(shape.len(), 5, |i, c| ((i * (c + 3)) % 17) as f64 - 8.0);
        let mut x = b.clone();
        mg.solve_in_place(x.as_mut(), false, TOLERANCE).unwrap();
        let r = system::apply(&shape, x.as_ref()) - &b;
        assert!(r.norm_l2() <= 1e-10 * b.norm_l2());
    }

    #[test]
    fn one_and_two_threads_give_the_same_bits() {
        // a disc of radius 80 (about 20k unknowns): its fine level (about 27k grid points)
        // and the next (about 7k) run their rows on several threads; every sum is added in
        // row order
        let shape = disc(80.0);
        let b = rhs(shape.len());
        let solve = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mg = Multigrid::new(&shape).unwrap();
                assert!(mg.levels[0].par() && mg.levels[1].par());
                let mut x = b.clone();
                let stats = mg.solve_in_place(x.as_mut(), false, TOLERANCE).unwrap();
                (x, stats.iterations)
            })
        };
        let (one, it1) = solve(1);
        for _ in 0..3 {
            let (two, it2) = solve(2);
            assert_eq!(it1, it2);
            let same = (0..one.ncols())
                .all(|c| (0..one.nrows()).all(|i| one[(i, c)].to_bits() == two[(i, c)].to_bits()));
            assert!(
                same,
                "the two-thread solution differs from the one-thread one"
            );
        }
    }

    #[test]
    fn the_galerkin_operator_is_pt_a_p() {
        // A_c e_J = Pᵀ A P e_J checked by applying the fine operator to the prolongated unit
        // vector, on an irregular mask
        let shape = mask(23, 19, |x, y| {
            (x - 11) * (x - 11) + 2 * (y - 9) * (y - 9) < 90 || (x == 3 && y > 2)
        });
        let mg = Multigrid::new(&shape).unwrap();
        let coarse = galerkin(&mg.levels[0]);
        let lays = [Layout::of(&mg.levels[0], false), Layout::of(&coarse, true)];
        let (fine, coarse) = (&mg.levels[0], &coarse);
        let Op::Stencil { index, table } = &coarse.op else {
            panic!("coarse levels are stencils")
        };
        let a: Vec<[f32; 9]> = index.iter().map(|&i| table[i as usize]).collect();
        let mut checked = 0;
        for yc in 1..coarse.h - 1 {
            for xc in 1..coarse.w - 1 {
                if !coarse.inside(yc, xc) {
                    continue;
                }
                let mut e = Grid::zeros(coarse.w, coarse.h);
                e.set(yc, xc, 1.0);
                let mut pe = Grid::zeros(fine.w, fine.h);
                let mut tmp = Grid::zeros(fine.w, fine.h);
                prolong_add(fine, coarse, &lays[0], &e, &mut Vec::new(), &mut pe);
                // Pᵀ (0 - A P e): the column of A_c, negated
                let mut col = Grid::zeros(coarse.w, coarse.h);
                restrict_residual(
                    fine,
                    coarse,
                    [&lays[0], &lays[1]],
                    &pe,
                    None,
                    false,
                    &mut tmp,
                    &mut Vec::new(),
                    &mut col,
                );
                for k in 0..9 {
                    let (y, x) = (yc + k / 3 - 1, xc + k % 3 - 1);
                    let want = -f64::from(col.get(y, x));
                    // the stencil of the neighbour reaching back to (yc, xc) (symmetry)
                    // stored in f32: equal up to its rounding, and exactly symmetric
                    let (ai, aj) = (a[yc * coarse.w + xc][k], a[y * coarse.w + x][8 - k]);
                    assert!((f64::from(ai) - want).abs() < 1e-6, "({yc},{xc}) {k}");
                    assert_eq!(ai, aj);
                }
                checked += 1;
            }
        }
        assert!(checked > 20);
    }

    #[test]
    fn convergence_per_cycle_on_a_disc_of_radius_100() {
        let shape = disc(100.0);
        let b = rhs(shape.len());
        // the plain V-cycle iteration: V(1,1) and V(2,2) (Trottenberg et al. 2001, table 2.4
        // give about 0.12 and 0.05 for red-black Gauss-Seidel on a square)
        for (sweeps, bound) in [(1, 0.3), (2, 0.2)] {
            let mg = Multigrid::new(&shape).unwrap().with_sweeps(sweeps);
            let rate = mg.vcycle_rate(b.as_ref(), 8);
            assert!(
                rate < bound,
                "V({sweeps},{sweeps}) convergence factor {rate:.3}"
            );
        }
        // conjugate gradients with one V(1,1) per iteration: residual 1e-11 in at most 12
        // iterations, a mean reduction per iteration below 0.15
        let mg = Multigrid::new(&shape).unwrap();
        let mut x = b.clone();
        let stats = mg.solve_in_place(x.as_mut(), false, TOLERANCE).unwrap();
        assert!(stats.iterations <= 12, "{stats:?}");
        let r = system::residual_norm(&shape, x.as_ref(), b.as_ref()) / b.norm_l2();
        assert!(
            r.powf(1.0 / stats.iterations as f64) < 0.15,
            "{r:.2e} {stats:?}"
        );
    }

    /// Convergence factors and timings of V(1,1) and V(2,2) on a 0.84-megapixel ellipse (not
    /// a check; run with `cargo test --release --lib multigrid_timing -- --ignored
    /// --nocapture`).
    #[test]
    #[ignore]
    fn multigrid_timing() {
        let shape = mask(1200, 900, |x, y| {
            let (dx, dy) = (
                (x as f64 + 0.5 - 600.0) / 597.0,
                (y as f64 + 0.5 - 450.0) / 447.0,
            );
            dx * dx + dy * dy < 1.0
        });
        let b = rhs(shape.len());
        // the plain cycle's convergence factor on the ellipse and on its bounding rectangle
        let rect = mask(1200, 900, |x, y| {
            (3..1197).contains(&x) && (3..897).contains(&y)
        });
        for (name, sh) in [("ellipse", &shape), ("rectangle", &rect)] {
            for sweeps in [1, 2] {
                let mg = Multigrid::new(sh).unwrap().with_sweeps(sweeps);
                let rate = mg.vcycle_rate(rhs(sh.len()).as_ref(), 10);
                eprintln!("{name}: V({sweeps},{sweeps}) convergence factor {rate:.3}");
            }
        }
        let t = std::time::Instant::now();
        let f = system::factor(&shape).unwrap();
        eprintln!("cholesky factor {:.0} ms", t.elapsed().as_secs_f64() * 1e3);
        for _ in 0..2 {
            let mut x = b.clone();
            let t = std::time::Instant::now();
            f.solve_in_place(x.as_mut());
            eprintln!("cholesky solve {:.0} ms", t.elapsed().as_secs_f64() * 1e3);
        }
        for sweeps in [1, 2, 1, 2] {
            let t = std::time::Instant::now();
            let mg = Multigrid::new(&shape).unwrap().with_sweeps(sweeps);
            let setup = t.elapsed().as_secs_f64() * 1e3;
            for warm in [true, true] {
                let mut x = b.clone();
                let t = std::time::Instant::now();
                let s = mg.solve_in_place(x.as_mut(), warm, TOLERANCE).unwrap();
                eprintln!(
                    "V({sweeps},{sweeps}) setup {setup:.0} ms, levels {:?}, solve {:.0} ms, {s:?}",
                    mg.unknowns(),
                    t.elapsed().as_secs_f64() * 1e3
                );
            }
        }
    }
}
