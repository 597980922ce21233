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
//! never share a 9-point stencil, so a colour is updated in parallel rows; on the 5-point
//! fine level this is red-black order). The pre-smoother runs the colours forwards and the
//! post-smoother backwards, so the V-cycle is a symmetric operator, as conjugate gradients
//! needs (Tatebe 1993, §2). The three colour channels are solved together, interleaved.
//!
//! Vectors live on the padded bounding box of each level (zero outside Ω), even and odd rows
//! in separate arrays, so that a colour's rows are written in parallel while the other
//! parity's rows are read, without `unsafe`.

use super::mask::MaskShape;
use crate::nodes::linalg::SpdFactor;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Mat, MatMut, Par};
use rayon::prelude::*;
use std::sync::Mutex;

mod coarsen;
mod grid;

use coarsen::*;
use grid::*;


/// A level with at most this many unknowns is solved directly (sparse Cholesky).
const COARSEST_MAX: usize = 1024;

/// Relative diagonal shift of the coarsest matrix (see the module comment).
const COARSE_SHIFT: f64 = 1e-10;

/// Grid points from which a level's sweeps run their rows on several threads.
const PAR_MIN: usize = 1 << 15;

/// Gauss-Seidel sweeps before and after the coarse correction (`Multigrid::sweeps`).
const SWEEPS: usize = 1;

/// Relative residual (`||b - A x|| / ||b||`, over all channels) conjugate gradients stops at:
/// below the node's requirement of 1e-10, with margin for the recurrence's drift.
pub const TOLERANCE: f64 = 5e-11;

/// Iterations after which conjugate gradients gives up (it needs about 10).
const MAX_ITERATIONS: usize = 200;


/// Per-level vectors of a V-cycle and the conjugate-gradient vectors, kept between solves.
struct Work {
    /// Per level: solution, right-hand side, residual.
    u: Vec<Field>,
    b: Vec<Field>,
    r: Vec<Field>,
    /// Conjugate gradients on the fine level: iterate, residual, direction, `A p`.
    x: Field,
    res: Field,
    p: Field,
    q: Field,
}

/// The multigrid hierarchy of one Ω: what the factorization cache keeps per mask shape.
pub struct Multigrid {
    levels: Vec<Level>,
    coarsest: Coarsest,
    /// Fine grid position `(y, x)` of unknown `k` (`MaskShape::inside` numbering).
    cells: Vec<[u32; 2]>,
    work: Mutex<Option<Work>>,
    /// Gauss-Seidel sweeps before and after each coarse correction.
    sweeps: usize,
    /// The last solution on the fine grid (one 3-channel group), a warm start for the next.
    last: Mutex<Option<Field>>,
}

/// What a multigrid solve did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    /// Conjugate-gradient iterations (one V-cycle each), the most of any 3-channel group.
    pub iterations: usize,
    /// Whether the previous solution was the starting guess.
    pub warm: bool,
}

impl Multigrid {
    /// The hierarchy of `shape`'s Poisson matrix: coarse levels by Galerkin products until a
    /// level has at most `COARSEST_MAX` unknowns or cannot be coarsened, which is factored.
    pub fn new(shape: &MaskShape) -> Result<Multigrid, String> {
        let Some([x0, y0, x1, y1]) = shape.bbox() else {
            return Err("the mask is empty".into());
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
        let mut levels = vec![Level {
            w,
            h,
            op: Op::Fine(inside),
            n: shape.len(),
        }];
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
            work: Mutex::new(None),
            sweeps: SWEEPS,
            last: Mutex::new(None),
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

    fn work(&self) -> Work {
        let f = |l: &Level| Field::zeros(l.w, l.h);
        let fine = &self.levels[0];
        Work {
            u: self.levels.iter().map(f).collect(),
            b: self.levels.iter().map(f).collect(),
            r: self.levels.iter().map(f).collect(),
            x: f(fine),
            res: f(fine),
            p: f(fine),
            q: f(fine),
        }
    }

    /// One symmetric V-cycle on level `l`: `u[l] ≈ A_l⁻¹ b[l]` from a zero start.
    fn vcycle(&self, l: usize, wk: &mut Work) {
        if l + 1 == self.levels.len() {
            self.coarsest.solve(&wk.b[l], &mut wk.u[l]);
            return;
        }
        let level = &self.levels[l];
        wk.u[l].fill_zero();
        for _ in 0..self.sweeps {
            for &(py, xs) in &COLOURS {
                smooth_rows(level, &mut wk.u[l], &wk.b[l], py, xs);
            }
        }
        residual(level, &wk.u[l], Some(&wk.b[l]), &mut wk.r[l]);
        restrict(level, &self.levels[l + 1], &wk.r[l], &mut wk.b[l + 1]);
        self.vcycle(l + 1, wk);
        {
            let (lo, hi) = wk.u.split_at_mut(l + 1);
            prolong_add(level, &hi[0], &mut lo[l]);
        }
        for _ in 0..self.sweeps {
            for &(py, [a, b]) in COLOURS.iter().rev() {
                smooth_rows(level, &mut wk.u[l], &wk.b[l], py, [b, a]);
            }
        }
    }

    /// `z = M r`: one V-cycle on the fine level from a zero start (the preconditioner).
    fn precondition(&self, wk: &mut Work) {
        std::mem::swap(&mut wk.b[0], &mut wk.res);
        self.vcycle(0, wk);
        std::mem::swap(&mut wk.b[0], &mut wk.res);
    }

    /// Solves `A X = B` in place, every column of `x` (in groups of three), by conjugate
    /// gradients preconditioned with one V-cycle per iteration, to a relative residual of
    /// `TOLERANCE`. With `warm`, the previous solution starts the iteration when its residual
    /// is below `||b||` (a repeated paste of the same shape).
    pub fn solve_in_place(&self, mut x: MatMut<'_, f64>, warm: bool) -> Result<Stats, String> {
        let mut own = None;
        let mut guard = self.work.try_lock();
        let wk = match guard.as_deref_mut() {
            Ok(w) => w.get_or_insert_with(|| self.work()),
            Err(_) => own.insert(self.work()),
        };
        let mut stats = Stats::default();
        let ncols = x.ncols();
        for g in (0..ncols).step_by(3) {
            let cols = (ncols - g).min(3);
            // b into the residual field, the warm start (or zero) into x
            wk.res.fill_zero();
            for (k, &[y, xx]) in self.cells.iter().enumerate() {
                let v = &mut wk.res.row_mut(y as usize)[xx as usize];
                for c in 0..cols {
                    v[c] = x[(k, g + c)];
                }
            }
            let reuse = warm && ncols == 3;
            let s = self.pcg(wk, reuse)?;
            stats.iterations = stats.iterations.max(s.iterations);
            stats.warm |= s.warm;
            for (k, &[y, xx]) in self.cells.iter().enumerate() {
                let v = wk.x.row(y as usize)[xx as usize];
                for c in 0..cols {
                    x[(k, g + c)] = v[c];
                }
            }
            if reuse {
                if let Ok(mut last) = self.last.try_lock() {
                    match last.as_mut() {
                        Some(f) => f.clone_from(&wk.x),
                        None => *last = Some(wk.x.clone()),
                    }
                }
            }
        }
        Ok(stats)
    }

    /// Preconditioned conjugate gradients, one per channel in lockstep, on `wk.res` = b;
    /// the solution in `wk.x`.
    fn pcg(&self, wk: &mut Work, warm: bool) -> Result<Stats, String> {
        let fine = &self.levels[0];
        let bn = norms(&wk.res);
        let bnorm = bn.iter().sum::<f64>().sqrt();
        let mut stats = Stats::default();
        wk.x.fill_zero();
        if bnorm == 0.0 {
            return Ok(stats);
        }
        let goal = TOLERANCE * bnorm;
        if warm {
            if let Ok(guard) = self.last.try_lock() {
                if let Some(last) = guard.as_ref() {
                    // r = b - A x_last, kept when it is smaller than b
                    residual(fine, last, Some(&wk.res), &mut wk.q);
                    if norms(&wk.q).iter().sum::<f64>() < bnorm * bnorm {
                        wk.x.clone_from(last);
                        std::mem::swap(&mut wk.res, &mut wk.q);
                        stats.warm = true;
                    }
                }
            }
        }
        let mut rn = norms(&wk.res).iter().sum::<f64>().sqrt();
        if rn <= goal {
            return Ok(stats);
        }
        // z = M r into u[0]; p = z
        self.precondition(wk);
        wk.p.clone_from(&wk.u[0]);
        let mut rz = dots(&wk.res, &wk.u[0]);
        while rn > goal {
            if stats.iterations >= MAX_ITERATIONS {
                return Err(format!(
                    "multigrid-preconditioned CG stopped after {MAX_ITERATIONS} iterations at a \
                     relative residual of {:.1e}",
                    rn / bnorm
                ));
            }
            stats.iterations += 1;
            let pq = residual(fine, &wk.p, None, &mut wk.q);
            let alpha = std::array::from_fn::<f64, 3, _>(|c| {
                if pq[c] > 0.0 && rz[c] > 0.0 {
                    rz[c] / pq[c]
                } else {
                    0.0
                }
            });
            rn = cg_update(fine, &mut wk.x, &mut wk.res, &wk.p, &wk.q, alpha)
                .iter()
                .sum::<f64>()
                .sqrt();
            if rn <= goal {
                break;
            }
            self.precondition(wk);
            let rz1 = dots(&wk.res, &wk.u[0]);
            let beta = std::array::from_fn::<f64, 3, _>(|c| {
                if rz[c] > 0.0 {
                    rz1[c] / rz[c]
                } else {
                    0.0
                }
            });
            rz = rz1;
            // p = z + β p
            let z = &wk.u[0];
            for p in 0..2 {
                let zr = &z.rows[p];
                let par = fine.par();
                let f = |(pv, zv): (&mut P3, &P3)| {
                    for c in 0..3 {
                        pv[c] = zv[c] + beta[c] * pv[c];
                    }
                };
                if par {
                    wk.p.rows[p].par_iter_mut().zip(zr.par_iter()).for_each(f);
                } else {
                    wk.p.rows[p].iter_mut().zip(zr.iter()).for_each(f);
                }
            }
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
            let v = &mut wk.q.row_mut(y as usize)[xx as usize];
            for c in 0..b.ncols().min(3) {
                v[c] = b[(k, c)];
            }
        }
        let target = wk.q.clone();
        let r0 = norms(&target).iter().sum::<f64>().sqrt();
        let mut r = r0;
        for _ in 0..cycles {
            residual(fine, &wk.x, Some(&target), &mut wk.res);
            self.precondition(&mut wk);
            update(fine, &mut wk.x, &wk.u[0], [1.0; 3]);
            residual(fine, &wk.x, Some(&target), &mut wk.res);
            r = norms(&wk.res).iter().sum::<f64>().sqrt();
        }
        (r / r0).powf(1.0 / cycles as f64)
    }
}

/// `a += s ∘ b` per channel.
fn update(level: &Level, a: &mut Field, b: &Field, s: P3) {
    for p in 0..2 {
        let f = |(av, bv): (&mut P3, &P3)| {
            for c in 0..3 {
                av[c] += s[c] * bv[c];
            }
        };
        if level.par() {
            a.rows[p].par_iter_mut().zip(b.rows[p].par_iter()).for_each(f);
        } else {
            a.rows[p].iter_mut().zip(b.rows[p].iter()).for_each(f);
        }
    }
}

/// Per-channel dot products of two fields (in parallel chunks for a large one).
fn dots(a: &Field, b: &Field) -> P3 {
    let add = |s: P3, t: P3| [s[0] + t[0], s[1] + t[1], s[2] + t[2]];
    let dot = |x: &[P3], y: &[P3]| {
        x.iter().zip(y).fold([0.0; 3], |s, (u, v)| {
            [s[0] + u[0] * v[0], s[1] + u[1] * v[1], s[2] + u[2] * v[2]]
        })
    };
    let mut s = [0.0; 3];
    for p in 0..2 {
        let (x, y) = (&a.rows[p], &b.rows[p]);
        let t = if x.len() >= PAR_MIN / 2 {
            x.par_chunks(1 << 13)
                .zip(y.par_chunks(1 << 13))
                .map(|(x, y)| dot(x, y))
                .reduce(|| [0.0; 3], add)
        } else {
            dot(x, y)
        };
        s = add(s, t);
    }
    s
}

/// Per-channel squared norms.
fn norms(a: &Field) -> P3 {
    dots(a, a)
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
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((i as f64) * 0.01 + c as f64).sin() + ((s >> 40) as f64 / (1u64 << 24) as f64 - 0.5)
        })
    }

    fn shapes() -> Vec<(&'static str, MaskShape)> {
        vec![
            ("disc", disc(40.0)),
            ("L-shape", mask(90, 80, |x, y| (x < 40 || y < 30) && x < 88 && y < 78)),
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
            ("touching the box (full box less a notch)", mask(70, 50, |x, y| !(x > 30 && y > 20 && x < 40))),
            ("single pixel", mask(3, 3, |x, y| x == 1 && y == 1)),
        ]
    }

    #[test]
    fn matches_cholesky_on_irregular_masks() {
        for (name, shape) in shapes() {
            let n = shape.len();
            let b = rhs(n);
            let mut reference = b.clone();
            system::factor(&shape).unwrap().solve_in_place(reference.as_mut());
            let mg = Multigrid::new(&shape).unwrap();
            for warm in [false, true, true] {
                let mut x = b.clone();
                let stats = mg.solve_in_place(x.as_mut(), warm).unwrap();
                let r = system::residual_norm(&shape, x.as_ref(), b.as_ref()) / b.norm_l2();
                assert!(r <= 1e-10, "{name}: residual {r:.2e} ({stats:?})");
                let e = (&x - &reference).norm_l2() / reference.norm_l2();
                assert!(e < 1e-9, "{name}: relative difference {e:.2e} from Cholesky");
            }
        }
    }

    #[test]
    fn the_hierarchy_coarsens_and_solves_more_than_three_columns() {
        let shape = disc(60.0);
        let mg = Multigrid::new(&shape).unwrap();
        let u = mg.unknowns();
        assert!(mg.depth() >= 3, "{u:?}");
        assert!(u.windows(2).all(|p| p[1] < p[0]) && *u.last().unwrap() <= COARSEST_MAX, "{u:?}");
        // five columns: a group of three and a group of two
        let b = Mat::from_fn(shape.len(), 5, |i, c| ((i * (c + 3)) % 17) as f64 - 8.0);
        let mut x = b.clone();
        mg.solve_in_place(x.as_mut(), false).unwrap();
        let r = system::apply(&shape, x.as_ref()) - &b;
        assert!(r.norm_l2() <= 1e-10 * b.norm_l2());
    }

    #[test]
    fn the_galerkin_operator_is_pt_a_p() {
        // A_c e_J = Pᵀ A P e_J checked by applying the fine operator to the prolongated unit
        // vector, on an irregular mask
        let shape = mask(23, 19, |x, y| (x - 11) * (x - 11) + 2 * (y - 9) * (y - 9) < 90 || (x == 3 && y > 2));
        let mg = Multigrid::new(&shape).unwrap();
        let (fine, coarse) = (&mg.levels[0], &galerkin(&mg.levels[0]));
        let Op::Stencil(a) = &coarse.op else { panic!("coarse levels are stencils") };
        let mut checked = 0;
        for yc in 1..coarse.h - 1 {
            for xc in 1..coarse.w - 1 {
                if !coarse.inside(yc, xc) {
                    continue;
                }
                let mut e = Field::zeros(coarse.w, coarse.h);
                e.row_mut(yc)[xc] = [1.0; 3];
                let mut pe = Field::zeros(fine.w, fine.h);
                prolong_add(fine, &e, &mut pe);
                let mut ape = Field::zeros(fine.w, fine.h);
                residual(fine, &pe, None, &mut ape);
                let mut col = Field::zeros(coarse.w, coarse.h);
                restrict(fine, coarse, &ape, &mut col);
                for k in 0..9 {
                    let (y, x) = (yc + k / 3 - 1, xc + k % 3 - 1);
                    let want = col.row(y)[x][0];
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
            assert!(rate < bound, "V({sweeps},{sweeps}) convergence factor {rate:.3}");
        }
        // conjugate gradients with one V(1,1) per iteration: residual 1e-11 in at most 12
        // iterations, a mean reduction per iteration below 0.15
        let mg = Multigrid::new(&shape).unwrap();
        let mut x = b.clone();
        let stats = mg.solve_in_place(x.as_mut(), false).unwrap();
        assert!(stats.iterations <= 12, "{stats:?}");
        let r = system::residual_norm(&shape, x.as_ref(), b.as_ref()) / b.norm_l2();
        assert!(r.powf(1.0 / stats.iterations as f64) < 0.15, "{r:.2e} {stats:?}");
    }

    /// Timings of V(1,1) and V(2,2) on a 0.84-megapixel ellipse (not a check; run with
    /// `cargo test --release --lib multigrid_timing -- --ignored --nocapture`).
    #[test]
    #[ignore]
    fn multigrid_timing() {
        let shape = mask(1200, 900, |x, y| {
            let (dx, dy) = ((x as f64 + 0.5 - 600.0) / 597.0, (y as f64 + 0.5 - 450.0) / 447.0);
            dx * dx + dy * dy < 1.0
        });
        let b = rhs(shape.len());
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
                let s = mg.solve_in_place(x.as_mut(), warm).unwrap();
                eprintln!(
                    "V({sweeps},{sweeps}) setup {setup:.0} ms, levels {:?}, solve {:.0} ms, {s:?}",
                    mg.unknowns(),
                    t.elapsed().as_secs_f64() * 1e3
                );
            }
        }
    }
}
