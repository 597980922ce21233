//! Poisson image editing (Pérez, Gangnet, Blake 2003, "Poisson Image Editing"): the source's
//! guidance field pasted into the target over a masked region Ω, solving the discrete
//! Poisson equation (eq. 7) with the target as Dirichlet values on ∂Ω.
//!
//! `mask.rs` holds Ω and its numbering, `system.rs` the matrix and its sparse Cholesky
//! factor, `rect.rs` the fast sine-transform solver for a rectangular Ω, `multigrid/` the
//! multigrid-preconditioned conjugate gradients for any Ω, `guidance.rs` the right-hand
//! side; this file the solver choice, the factorization cache and the solve. The matrix depends only
//! on the shape of Ω, so its factorization is kept in a small process-wide cache keyed by the
//! shape up to translation: a sequence of pastes that only moves the offset (the course's
//! interactive dragging) or changes the images solves without refactoring.

pub mod guidance;
pub mod mask;
pub mod multigrid;
pub mod rect;
pub mod system;
#[cfg(test)]
mod timing;

pub use guidance::Mode;
pub use mask::{MaskShape, ShapeKey};

use super::NonFinitePixel;
use cgnodes_api::types::Image;
use faer::reborrow::ReborrowMut;
use faer::Mat;
use rayon::prelude::*;
use rect::RectSolver;
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Relative residual `‖b − A x‖ / ‖b‖` at which multigrid stops by default (the node's
/// `tolerance`). On the course paste the largest pixel error against the exact discrete
/// solution is about the relative residual: at 1e-5, 5 cold iterations and 5.2e-6 (seamless;
/// a 750th of an 8-bit level), where 8e-11 takes 9 (test
/// `default_tolerance_is_within_1e5_of_the_exact_course_paste`).
pub const DEFAULT_TOLERANCE: f64 = 1e-5;

/// How many factorizations the cache keeps (least recently used dropped first).
pub const CACHE_SLOTS: usize = 4;

/// Which solver a paste uses (the node's `solver` parameter).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Solver {
    /// The sine transform for a rectangle, else `auto_solver`'s choice.
    Auto,
    /// Sparse Cholesky (any Ω).
    Cholesky,
    /// Multigrid-preconditioned conjugate gradients (any Ω).
    Multigrid,
    /// The sine-transform solver (a rectangular Ω only).
    SineTransform,
}

impl cgnodes_api::node::Choice for Solver {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("auto", Solver::Auto),
        ("cholesky", Solver::Cholesky),
        ("multigrid", Solver::Multigrid),
        ("sine_transform", Solver::SineTransform),
    ];
}

/// Unknowns below which `auto` factors by Cholesky rather than building a multigrid
/// hierarchy (measured in docs/image.md: on small masks the factorization is cheap and its
/// solve beats a dozen V-cycles).
pub const MULTIGRID_MIN_UNKNOWNS: usize = 4096;

/// Pastes of one shape that `auto` answers by multigrid before it factors by Cholesky instead,
/// for a shape below `system::ND_MIN_UNKNOWNS` unknowns: multigrid's first paste is the
/// cheaper (no factorization), Cholesky's repeated one (two triangular solves against about
/// ten V-cycles), so a long drag of one shape switches, as in the ski-rental rule (Karlin et
/// al. 1988, "Competitive snoopy caching"): pay the extra cost of the cheaper-to-start option
/// until it adds up to the price of the other's start (here the factorization). On the course
/// mask (14.9k unknowns) a factorization costs about 25-40 ms and a multigrid paste about
/// 11 ms more than a reused Cholesky one (docs/image.md).
pub const AUTO_CHOLESKY_AFTER: usize = 3;

/// `AUTO_CHOLESKY_AFTER` for a shape of at least `system::ND_MIN_UNKNOWNS` unknowns: on the
/// 0.84-megapixel ellipse the first Cholesky paste takes about 0.74 s and a reused one 0.13 s
/// (so the factorization about 0.6 s), a multigrid paste about 0.22 s, 0.09 s more than a
/// reused Cholesky one: 0.6 / 0.09 ≈ 6 pastes (docs/image.md).
pub const AUTO_CHOLESKY_AFTER_LARGE: usize = 6;

/// How many multigrid pastes `auto` makes of a shape of `unknowns` before it factors.
pub fn auto_cholesky_after(unknowns: usize) -> usize {
    if unknowns < system::ND_MIN_UNKNOWNS {
        AUTO_CHOLESKY_AFTER
    } else {
        AUTO_CHOLESKY_AFTER_LARGE
    }
}

/// The solver `auto` picks for `shape`: the sine transform for a rectangle, multigrid for a
/// large Ω that fills at least a quarter of its bounding box (multigrid works on the box's
/// grid), sparse Cholesky otherwise.
pub fn auto_solver(shape: &MaskShape) -> Solver {
    if shape.rectangle().is_some() {
        return Solver::SineTransform;
    }
    let area = shape.bbox().map_or(0, |[x0, y0, x1, y1]| {
        (x1 - x0 + 1) as usize * (y1 - y0 + 1) as usize
    });
    if shape.len() >= MULTIGRID_MIN_UNKNOWNS && 4 * shape.len() >= area {
        Solver::Multigrid
    } else {
        Solver::Cholesky
    }
}

/// The factorization of one shape's Poisson matrix.
pub enum Factor {
    /// Sparse Cholesky (faer; AMD or nested-dissection ordering): any Ω.
    Cholesky(Box<system::PoissonFactor>),
    /// Sine transform along rows and tridiagonal pivots down columns: a rectangular Ω.
    Rect(RectSolver),
    /// The multigrid hierarchy (coarse levels and their operators): any Ω.
    Multigrid(Box<multigrid::Multigrid>),
}

impl Factor {
    /// Factors the Poisson matrix of `shape`: the fast solver for a rectangle, else Cholesky.
    pub fn new(shape: &MaskShape) -> Result<Factor, PoissonError> {
        Factor::with(shape, Solver::Auto)
    }

    /// Factors the Poisson matrix of `shape` for `solver` (`Auto` resolved by `auto_solver`);
    /// `SineTransform` for an Ω that is not a rectangle is an error.
    pub fn with(shape: &MaskShape, solver: Solver) -> Result<Factor, PoissonError> {
        let solver = match solver {
            Solver::Auto => auto_solver(shape),
            s => s,
        };
        Ok(match solver {
            Solver::SineTransform => match shape.rectangle() {
                Some([w, h]) => Factor::Rect(RectSolver::new(w as usize, h as usize)),
                None => return Err(PoissonError::NotARectangle),
            },
            Solver::Multigrid => Factor::Multigrid(Box::new(multigrid::Multigrid::new(shape)?)),
            _ => Factor::Cholesky(Box::new(system::factor(shape)?)),
        })
    }

    /// Solves `A X = B` in place, every column of `x` (one per channel); the multigrid
    /// iterations (0 for a direct solver) and its relative residual (`None` for a direct
    /// solver). The multigrid starts from the previous solution of the same shape when that
    /// is closer than zero and stops at a relative residual of `tolerance`; the direct
    /// solvers are exact up to rounding.
    pub fn solve_in_place(
        &self,
        mut x: faer::MatMut<'_, f64>,
        tolerance: f64,
    ) -> Result<(usize, Option<f64>), PoissonError> {
        match self {
            Factor::Cholesky(f) => f.solve_in_place(x),
            Factor::Multigrid(m) => {
                let s = m.solve_in_place(x, true, tolerance)?;
                return Ok((s.iterations, Some(s.relative_residual())));
            }
            Factor::Rect(f) => {
                // the channels are independent: one per task
                let mut cols: Vec<_> = x.as_mut().col_iter_mut().collect();
                cols.par_iter_mut()
                    .for_each(|col| match col.rb_mut().try_as_col_major_mut() {
                        Some(col) => f.solve_in_place(col.as_slice_mut()),
                        None => {
                            // a strided view: solve a contiguous copy
                            let mut v: Vec<f64> = col.as_ref().iter().copied().collect();
                            f.solve_in_place(&mut v);
                            col.rb_mut().iter_mut().zip(v).for_each(|(d, s)| *d = s);
                        }
                    });
            }
        }
        Ok((0, None))
    }

    /// Which solver this is, for the table (`cholesky`, `sine_transform` or `multigrid`).
    pub fn name(&self) -> &'static str {
        match self {
            Factor::Cholesky(_) => "cholesky",
            Factor::Rect(_) => "sine_transform",
            Factor::Multigrid(_) => "multigrid",
        }
    }
}

/// Why a Poisson paste cannot be factored or solved.
#[derive(Debug, thiserror::Error)]
pub enum PoissonError {
    /// The mask has no pixel inside (multigrid).
    #[error("the mask is empty")]
    EmptyMask,
    /// `solver: sine_transform` for an Ω that is not a rectangle.
    #[error(
        "solver 'sine_transform' needs a rectangular mask (every pixel of its bounding box \
         inside); this mask is not one: use auto, cholesky or multigrid"
    )]
    NotARectangle,
    /// The sparse Cholesky factorization failed (cgnodes-linalg's error).
    #[error("{0}")]
    Factor(crate::BoxedError),
    /// Multigrid-preconditioned CG reached its iteration limit above the tolerance.
    #[error(
        "multigrid-preconditioned CG stopped after {iterations} iterations at a relative \
         residual of {residual:.1e}"
    )]
    NoConvergence { iterations: usize, residual: f64 },
    /// Ω's bounding box (with its border) does not fit inside the target.
    #[error("the mask region does not fit inside the target")]
    DoesNotFit,
    /// The offset puts Ω's border outside the target.
    #[error("offset {offset:?} outside {x_range:?} x {y_range:?}")]
    OffsetOutside {
        offset: [i64; 2],
        x_range: [i64; 2],
        y_range: [i64; 2],
    },
    /// The source image and the mask have different sizes.
    #[error("source and mask sizes differ")]
    SizeMismatch,
    /// A pixel of the target is not finite (`copy_target`).
    #[error(transparent)]
    NonFinite(#[from] NonFinitePixel),
}

/// Cache entries: (shape, solver), the factorization, and how many pastes asked for it.
type Cache = Vec<((ShapeKey, Solver), Arc<Factor>, usize)>;
static CACHE: Mutex<Cache> = Mutex::new(Vec::new());

/// The factorization of `shape`'s Poisson matrix, from the cache when a mask of the same
/// shape was factored recently; the flag says whether it was reused.
pub fn cached_factor(shape: &MaskShape) -> Result<(Arc<Factor>, bool), PoissonError> {
    cached_factor_keyed(shape, &shape.key(), Solver::Auto)
}

/// `cached_factor` with the shape's key found already, for `solver` (`Auto` resolved first,
/// so that `auto` and the solver it picks share the cache entry).
pub fn cached_factor_keyed(
    shape: &MaskShape,
    key: &ShapeKey,
    solver: Solver,
) -> Result<(Arc<Factor>, bool), PoissonError> {
    let auto = solver == Solver::Auto;
    let mut solver = match solver {
        Solver::Auto => auto_solver(shape),
        s => s,
    };
    let mg_key = (key.clone(), Solver::Multigrid);
    {
        let mut cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
        if auto && solver == Solver::Multigrid {
            // the ski-rental switch: a shape pasted often enough goes to Cholesky
            let uses = cache.iter().find(|(k, ..)| *k == mg_key).map_or(0, |e| e.2);
            if uses >= auto_cholesky_after(shape.len()) {
                solver = Solver::Cholesky;
            }
        }
        let key = (key.clone(), solver);
        if let Some(i) = cache.iter().position(|(k, ..)| *k == key) {
            // move to the back: most recently used
            let mut entry = cache.remove(i);
            entry.2 += 1;
            let f = entry.1.clone();
            cache.push(entry);
            return Ok((f, true));
        }
    }
    let key = (key.clone(), solver);
    // factored outside the lock: another paste may run meanwhile
    let f = Arc::new(Factor::with(shape, solver)?);
    let mut cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
    if !cache.iter().any(|(k, ..)| *k == key) {
        // evict the least recently used, but not the multigrid entry whose count keeps
        // `auto` on the Cholesky factor just made
        while cache.len() >= CACHE_SLOTS {
            let i = cache.iter().position(|(k, ..)| *k != mg_key).unwrap_or(0);
            cache.remove(i);
        }
        cache.push((key, f.clone(), 1));
    }
    Ok((f, false))
}

/// A matrix kept between pastes so that the next one reuses its memory instead of fresh,
/// page-faulted pages; `take` and `keep` skip it when another paste holds it.
struct Spare(Mutex<Option<Mat<f64>>>);

impl Spare {
    const fn new() -> Spare {
        Spare(Mutex::new(None))
    }

    /// The kept matrix, or an empty one.
    fn take(&self) -> Mat<f64> {
        self.0
            .try_lock()
            .ok()
            .and_then(|mut k| k.take())
            .unwrap_or_else(Mat::new)
    }

    /// Keeps `m` for the next `take`.
    fn keep(&self, m: Mat<f64>) {
        if let Ok(mut k) = self.0.try_lock() {
            *k = Some(m);
        }
    }
}

/// The last paste's right-hand side buffer (`n x 3`): at a megapixel it is 25 MB that would
/// otherwise be fresh memory, page-faulted in again on every paste.
static RHS_BUFFER: Spare = Spare::new();

/// A solution matrix given back (`recycle`) once its values are in the image, for the next
/// paste to solve in: on the course mask a fresh one cost 0.13-0.15 ms of page faults.
static SOLUTION_BUFFER: Spare = Spare::new();

/// Gives a solved paste's values back for the next paste's solve (see `SOLUTION_BUFFER`).
pub fn recycle(values: Mat<f64>) {
    SOLUTION_BUFFER.keep(values);
}

/// A solved paste: the values of the unknowns before they are written into the image.
#[derive(Clone, Debug)]
pub struct Solution {
    /// `n x 3`: the RGB value of inside pixel `k` (see `MaskShape::inside`), in f64.
    pub values: Mat<f64>,
    /// `||b - A x|| / ||b||` (Frobenius over the three channels; `||b - A x||` when b = 0):
    /// multigrid's from its conjugate-gradient recurrence (within 1 % of the recomputed one,
    /// tested), the direct solvers' recomputed.
    pub residual: f64,
    /// Whether the factorization came from the cache.
    pub reused: bool,
    /// Which solver ran (`Factor::name`).
    pub solver: &'static str,
    /// Multigrid-preconditioned CG iterations (0 for the direct solvers).
    pub iterations: usize,
    /// Wall time of the solve (right-hand side, factorization or lookup, solve, residual).
    pub millis: f64,
}

/// Solves the Poisson paste of `source` over Ω = `shape` into `target` with the source's
/// top-left corner at target pixel `offset`. Ω must be non-empty and `offset` within
/// `shape.offset_range` (else `Err`, as for a failed factorization).
pub fn solve(
    shape: &MaskShape,
    target: &Image,
    source: &Image,
    offset: [i64; 2],
    mode: Mode,
) -> Result<Solution, PoissonError> {
    solve_keyed(
        shape,
        &shape.key(),
        target,
        source,
        offset,
        mode,
        Solver::Auto,
        DEFAULT_TOLERANCE,
    )
}

/// `solve` with the shape's key (`MaskShape::key`) found already, by `solver`, multigrid
/// stopping at a relative residual of `tolerance`.
#[allow(clippy::too_many_arguments)]
pub fn solve_keyed(
    shape: &MaskShape,
    key: &ShapeKey,
    target: &Image,
    source: &Image,
    offset: [i64; 2],
    mode: Mode,
    solver: Solver,
    tolerance: f64,
) -> Result<Solution, PoissonError> {
    let t0 = Instant::now();
    let Some([xr, yr]) = shape.offset_range(target.width, target.height) else {
        return Err(PoissonError::DoesNotFit);
    };
    if !(xr[0]..=xr[1]).contains(&offset[0]) || !(yr[0]..=yr[1]).contains(&offset[1]) {
        return Err(PoissonError::OffsetOutside {
            offset,
            x_range: xr,
            y_range: yr,
        });
    }
    if (source.width, source.height) != (shape.width, shape.height) {
        return Err(PoissonError::SizeMismatch);
    }
    // the right-hand side (in the last paste's buffer when it is free, see `RHS_BUFFER`)
    // beside the factorization or hierarchy of a new shape: they are independent
    let (b, factor) = rayon::join(
        || {
            let mut b = RHS_BUFFER.take();
            guidance::right_hand_side_into(shape, target, source, offset, mode, &mut b);
            b
        },
        || cached_factor_keyed(shape, key, solver),
    );
    let (factor, reused) = factor?;
    let mut x = copy_of_rhs(&b);
    let (iterations, recurrence) = factor.solve_in_place(x.as_mut(), tolerance)?;
    // multigrid's own residual (its conjugate-gradient recurrence), else recomputed
    let residual = recurrence.unwrap_or_else(|| relative_residual(shape, x.as_ref(), b.as_ref()));
    RHS_BUFFER.keep(b);
    Ok(Solution {
        values: x,
        residual,
        reused,
        solver: factor.name(),
        iterations,
        millis: t0.elapsed().as_secs_f64() * 1e3,
    })
}

/// A copy of `b` to solve in place, in the last solution's memory when it was given back
/// (`recycle`).
fn copy_of_rhs(b: &Mat<f64>) -> Mat<f64> {
    let mut x = SOLUTION_BUFFER.take();
    shape_mat(&mut x, b.nrows(), b.ncols());
    x.copy_from(b);
    x
}

/// Makes `m` an `n x k` matrix in its own memory when it fits: a new shape's paste then
/// writes into the last paste's pages instead of fresh ones (on the course mask each of the
/// right-hand side and the solution was 87 page faults, some 0.12 ms). New memory holds a
/// quarter more rows than asked, so that a slightly larger shape fits it next time; memory
/// more than four times too large is given back. Rows added in the same memory are zero;
/// the callers write every entry.
pub(crate) fn shape_mat(m: &mut Mat<f64>, n: usize, k: usize) {
    if (m.nrows(), m.ncols()) == (n, k) {
        return;
    }
    // a matrix's column stride is its row capacity
    let capacity = if m.ncols() > 1 {
        m.as_ref().col_stride().unsigned_abs()
    } else {
        0
    };
    if capacity < n || m.ncols() < k || capacity > 4 * n.max(1024) {
        *m = Mat::with_capacity(n + n / 4, k);
    }
    m.resize_with(n, k, |_, _| 0.0);
}

/// `||b - A x|| / ||b||` over all channels (`||b - A x||` when b = 0).
pub fn relative_residual(
    shape: &MaskShape,
    x: faer::MatRef<'_, f64>,
    b: faer::MatRef<'_, f64>,
) -> f64 {
    let r = system::residual_norm(shape, x, b);
    // plain sum of squares: pixel-sized values cannot overflow (faer's scaled norm took
    // longer than the residual itself at 1 megapixel)
    let bn = (0..b.ncols())
        .into_par_iter()
        .map(|c| b.col(c).iter().map(|v| v * v).sum::<f64>())
        .collect::<Vec<f64>>()
        .iter()
        .sum::<f64>()
        .sqrt();
    if bn > 0.0 {
        r / bn
    } else {
        r
    }
}

/// A copy of `target`, checked as it is copied (its first non-finite pixel is an error):
/// a paste runs it on the other core while it solves (the copy's fresh pages cost about as
/// much as the course mask's solve), then `write_solution` puts the solved values over Ω.
pub fn copy_target(target: &Image) -> Result<Image, NonFinitePixel> {
    let mut out = Image::new(target.width, target.height, [0.0; 4]);
    let tw = (target.width as usize).max(1);
    let bad = std::sync::atomic::AtomicBool::new(false);
    out.pixels
        .par_chunks_mut(tw)
        .zip(target.pixels.par_chunks(tw))
        .with_max_len(COPY_ROWS)
        .for_each(|(row, src)| {
            row.copy_from_slice(src);
            if super::any_non_finite(src) {
                bad.store(true, std::sync::atomic::Ordering::Relaxed);
            }
        });
    if bad.into_inner() {
        super::check_finite(target)?;
    }
    Ok(out)
}

/// Rows per task of `copy_target` at most: small tasks, so that the solving core takes
/// over part of the copy when it finishes first.
const COPY_ROWS: usize = 8;

/// The solved RGB values written over Ω in `out` (a copy of the target, `copy_target`),
/// alpha kept; not clamped (the image is linear; `image_save` clamps when it encodes).
pub fn write_solution(out: &mut Image, shape: &MaskShape, offset: [i64; 2], values: &Mat<f64>) {
    let (tw, mw) = ((out.width as usize).max(1), shape.width as usize);
    out.pixels
        .par_chunks_mut(tw)
        .enumerate()
        .for_each(|(ty, row)| {
            let my = ty as i64 - offset[1];
            if my < 0 || my >= i64::from(shape.height) {
                return;
            }
            let index = &shape.index[my as usize * mw..(my as usize + 1) * mw];
            for (mx, &k) in index.iter().enumerate() {
                if k == u32::MAX {
                    continue;
                }
                let p = &mut row[(mx as i64 + offset[0]) as usize];
                for (c, v) in p.iter_mut().take(3).enumerate() {
                    *v = values[(k as usize, c)] as f32;
                }
            }
        });
}

/// Runs `f` while another thread of the pool waits for its parallel pieces awake.
///
/// Rayon puts an idle worker to sleep after about 32 empty polls (some 20 µs here), and the
/// next parallel loop pays a futex wake-up, which on the bench machine (a virtual machine)
/// costs more than a multigrid smoothing sweep of the course mask: a paste's short serial
/// stretches (the coarse levels, the scalar steps of conjugate gradients) put the worker to
/// sleep about eight times per solve (context switches counted with `getrusage` on the course
/// mask). The companion instead polls with `rayon::yield_now`, which runs whatever piece `f`
/// (or anyone) has posted, until `f` returns; it spins while `f` is serial, and a piece of
/// another node's work it picks up is finished before it stops. With one thread the companion
/// runs after `f`, finds it done and returns.
pub fn with_companion<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    use std::sync::atomic::{AtomicBool, Ordering};
    /// Sets the flag when dropped: on return and on unwinding alike, so the companion never
    /// outlives a panicking `f` (`rayon::join` waits for both sides before it re-panics).
    struct Done<'a>(&'a AtomicBool);
    impl Drop for Done<'_> {
        fn drop(&mut self) {
            self.0.store(true, Ordering::Release);
        }
    }
    let done = AtomicBool::new(false);
    let (r, ()) = rayon::join(
        || {
            let _done = Done(&done);
            f()
        },
        || {
            while !done.load(Ordering::Acquire) {
                if rayon::yield_now() != Some(rayon::Yield::Executed) {
                    std::hint::spin_loop();
                }
            }
        },
    );
    r
}

#[cfg(test)]
mod companion_tests {
    use super::with_companion;
    use rayon::prelude::*;
    use std::sync::mpsc;
    use std::time::Duration;

    /// Runs `f` on a pool of `threads` on its own thread; `None` if it has not returned
    /// within 30 s (a companion that never stops).
    fn bounded<R: Send + 'static>(
        threads: usize,
        f: impl FnOnce() -> R + Send + 'static,
    ) -> Option<std::thread::Result<R>> {
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a pool");
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| pool.install(f)));
            let _ = tx.send(r);
        });
        rx.recv_timeout(Duration::from_secs(30)).ok()
    }

    #[test]
    fn companion_returns_the_result_on_one_and_two_threads() {
        for threads in [1, 2] {
            let r = bounded(threads, || {
                with_companion(|| (0..100_000u64).into_par_iter().map(|i| i * i).sum::<u64>())
            });
            let expected: u64 = (0..100_000u64).map(|i| i * i).sum();
            assert_eq!(r.expect("returned").expect("no panic"), expected);
        }
    }

    #[test]
    fn companion_stops_when_the_work_panics() {
        for threads in [1, 2] {
            let r = bounded(threads, || {
                with_companion(|| -> u32 {
                    (0..64u32)
                        .into_par_iter()
                        .for_each(|i| assert!(i < 63, "a bad piece"));
                    0
                })
            });
            assert!(
                r.expect("returned, not spinning").is_err(),
                "the panic propagates"
            );
        }
    }
}

#[cfg(test)]
mod shape_mat_tests {
    use super::shape_mat;
    use faer::Mat;

    #[test]
    fn a_shape_that_fits_keeps_the_memory() {
        let mut m = Mat::<f64>::new();
        shape_mat(&mut m, 100, 3);
        assert_eq!((m.nrows(), m.ncols()), (100, 3));
        let p = m.as_ptr();
        m.as_mut().fill(7.0);
        // smaller, then larger within the quarter kept in reserve: the same memory
        shape_mat(&mut m, 90, 3);
        assert_eq!((m.nrows(), m.as_ptr()), (90, p));
        shape_mat(&mut m, 120, 3);
        assert_eq!((m.nrows(), m.as_ptr()), (120, p));
        for c in 0..3 {
            assert!((0..90).all(|i| m[(i, c)] == 7.0));
            assert!((90..120).all(|i| m[(i, c)] == 0.0));
        }
        // beyond the reserve: new memory
        shape_mat(&mut m, 20_000, 3);
        assert_eq!((m.nrows(), m.ncols()), (20_000, 3));
        assert_ne!(m.as_ptr(), p);
        // far smaller than the memory (more than four times): the memory is given back
        let p = m.as_ptr();
        shape_mat(&mut m, 1000, 3);
        assert_ne!(m.as_ptr(), p);
        assert_eq!((m.nrows(), m.ncols()), (1000, 3));
    }
}
