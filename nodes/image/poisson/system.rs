//! The discrete Poisson matrix over Ω (Pérez et al. 2003, eq. 7): for each inside pixel p,
//! `|N_p| f_p - Σ_{q ∈ N_p ∩ Ω} f_q = (Dirichlet values and guidance, see guidance.rs)`.
//! Ω never touches the target's border, so |N_p| = 4 everywhere: 4 on the diagonal, -1 for
//! each inside 4-neighbour. The matrix is symmetric, diagonally dominant, and strictly so at
//! each pixel next to ∂Ω, hence positive definite (every component of Ω touches ∂Ω).
//!
//! Its sparse Cholesky factor (faer) is found in one of two elimination orders: faer's AMD for
//! small Ω, and for large Ω a nested dissection of the pixel grid (George 1973), whose
//! separators are whole grid lines and whose two top-level halves are factored on two cores
//! and joined through the dense Schur complement of the top separator (`TwoDomainFactor`).

use super::mask::MaskShape;
use super::PoissonError;
use cgnodes_linalg::nested_dissection::Dissection;
use cgnodes_linalg::{SpdFactor, TwoDomainFactor};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Mat, MatMut, MatRef, Par};
use rayon::prelude::*;
use std::sync::Mutex;

/// The lower triangle of the Poisson matrix in compressed columns. Unknowns are numbered
/// row-major, so column k holds the diagonal, then the right neighbour, then the one below
/// (rows already sorted).
pub fn poisson_matrix(shape: &MaskShape) -> SparseColMat<usize, f64> {
    let n = shape.len();
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::with_capacity(3 * n);
    let mut values = Vec::with_capacity(3 * n);
    col_ptr.push(0usize);
    for (k, &[x, y]) in shape.inside.iter().enumerate() {
        row_idx.push(k);
        values.push(4.0);
        for (dx, dy) in [(1, 0), (0, 1)] {
            if let Some(q) = shape.unknown(x as i64 + dx, y as i64 + dy) {
                row_idx.push(q);
                values.push(-1.0);
            }
        }
        col_ptr.push(row_idx.len());
    }
    let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
    SparseColMat::new(symbolic, values)
}

/// Unknowns from which the matrix is factored in a nested-dissection order instead of AMD.
/// Measured (process CPU time of the factorization, see docs/image.md): AMD 16-17 ms against
/// 22-24 ms for nested dissection on the course's 14,860-pixel mask; 1.67-1.71 s against
/// 1.27-1.29 s on the 838,781-pixel ellipse, whose halves then also factor on two cores.
pub const ND_MIN_UNKNOWNS: usize = 100_000;

/// Dissection sets of at most this many pixels keep row-major order.
const ND_LEAF: usize = 64;

/// Both top-level halves need this many unknowns to be factored as two domains.
const TWO_DOMAIN_MIN: usize = 4096;

/// Factors the Poisson matrix of `shape` (sparse Cholesky): faer's AMD ordering below
/// `ND_MIN_UNKNOWNS` unknowns, else the grid's nested dissection (`nested_order`), whose two
/// top-level halves are factored on two cores (`TwoDomainFactor`).
pub fn factor(shape: &MaskShape) -> Result<PoissonFactor, PoissonError> {
    if shape.len() < ND_MIN_UNKNOWNS {
        let f = SpdFactor::from_lower(poisson_matrix(shape), None, Par::Seq)
            .map_err(|e| PoissonError::Factor(e.into()))?;
        return Ok(PoissonFactor {
            kind: Kind::Amd(f),
            order: Vec::new(),
            scratch: Mutex::new(Mat::new()),
            work3: Mutex::new(Vec::new()),
        });
    }
    factor_nested(shape, ND_LEAF, TWO_DOMAIN_MIN)
}

/// `factor` in the grid's nested-dissection order, the top-level halves as two domains when
/// both have at least `two_min` unknowns.
fn factor_nested(
    shape: &MaskShape,
    leaf: usize,
    two_min: usize,
) -> Result<PoissonFactor, PoissonError> {
    let n = shape.len();
    let Dissection { order, halves } = nested_order(shape, leaf);
    let a = upper_in_order(shape, &order);
    let kind = match halves {
        Some([h0, h1]) if h0.min(h1) >= two_min && h0 + h1 < n => Kind::Two(
            TwoDomainFactor::from_upper_in_order(a.as_ref(), h0, h1)
                .map_err(|e| PoissonError::Factor(e.into()))?,
        ),
        _ => Kind::One(
            SpdFactor::from_upper_in_order(a, Par::Seq)
                .map_err(|e| PoissonError::Factor(e.into()))?,
        ),
    };
    Ok(PoissonFactor {
        kind,
        order: order.iter().map(|&v| v as u32).collect(),
        scratch: Mutex::new(Mat::new()),
        work3: Mutex::new(Vec::new()),
    })
}

/// The sparse Cholesky factor of a mask's Poisson matrix, with its elimination order.
pub struct PoissonFactor {
    kind: Kind,
    /// For a nested-dissection factor, `order[k]` is the unknown eliminated `k`-th (empty
    /// for AMD, whose permutation `SpdFactor` applies itself).
    order: Vec<u32>,
    /// The right-hand sides in elimination order, kept between solves (no fresh pages).
    scratch: Mutex<Mat<f64>>,
    /// `SpdFactor::solve3`'s interleaved values, kept between solves.
    work3: Mutex<Vec<[f64; 3]>>,
}

/// One factor (AMD, or nested dissection on one core) or two domains and their separator.
#[allow(clippy::large_enum_variant)]
enum Kind {
    Amd(SpdFactor),
    One(SpdFactor),
    Two(TwoDomainFactor),
}

impl PoissonFactor {
    /// Solves `A X = B` in place, every column of `x` (one per channel).
    pub fn solve_in_place(&self, mut x: MatMut<'_, f64>) {
        if let Kind::Amd(f) = &self.kind {
            // three channels at once on this core (the caller copies the target on the other)
            if let Ok(mut w) = self.work3.try_lock() {
                if f.solve3(x.as_mut(), &mut w) {
                    return;
                }
            }
        }
        let (f, two) = match &self.kind {
            Kind::Amd(f) if x.nrows() >= SPLIT_SOLVE_ROWS && x.ncols() > 1 => {
                let (a, b) = x.split_at_col_mut(1);
                rayon::join(|| f.solve_in_place(a), || f.solve_in_place(b));
                return;
            }
            Kind::Amd(f) => return f.solve_in_place(x),
            Kind::One(f) => (Some(f), None),
            Kind::Two(f) => (None, Some(f)),
        };
        let (n, k) = (x.nrows(), x.ncols());
        let mut own = Mat::new();
        let mut guard = self.scratch.try_lock();
        let y = match guard.as_deref_mut() {
            Ok(m) => m,
            Err(_) => &mut own,
        };
        if (y.nrows(), y.ncols()) != (n, k) {
            *y = Mat::zeros(n, k);
        }
        // gather into elimination order, solve, scatter back (column by column)
        for c in 0..k {
            let (src, dst) = (x.as_ref().col(c), y.as_mut().col_mut(c));
            for (d, &v) in dst.iter_mut().zip(&self.order) {
                *d = src[v as usize];
            }
        }
        match (f, two) {
            (Some(f), _) if n >= SPLIT_SOLVE_ROWS && k > 1 => {
                // the triangular solves are memory-bound: a column on one core, the rest on
                // the other (both read the same factor)
                let (a, b) = y.as_mut().split_at_col_mut(1);
                rayon::join(
                    || f.solve_in_elimination_order(a),
                    || f.solve_in_elimination_order(b),
                );
            }
            (Some(f), _) => f.solve_in_elimination_order(y.as_mut()),
            (None, Some(t)) => t.solve_in_place(y.as_mut()),
            (None, None) => unreachable!("one of the two factors is set"),
        }
        for c in 0..k {
            let (src, mut dst) = (y.as_ref().col(c), x.as_mut().col_mut(c));
            for (s, &v) in src.iter().zip(&self.order) {
                dst[v as usize] = *s;
            }
        }
    }

    /// Which ordering the factor used (`amd` or `nested_dissection`).
    pub fn ordering(&self) -> &'static str {
        match self.kind {
            Kind::Amd(_) => "amd",
            _ => "nested_dissection",
        }
    }

    /// Whether the two top-level halves were factored as two domains.
    pub fn two_domains(&self) -> bool {
        matches!(self.kind, Kind::Two(_))
    }
}

/// Unknowns from which a one-factor solve runs its columns on two cores.
const SPLIT_SOLVE_ROWS: usize = 4096;

/// A nested-dissection order of Ω's unknowns (George 1973, "Nested dissection of a regular
/// finite element mesh"), for the pixel grid: the pixels are split by the grid line (a row or
/// a column) at the median of their wider extent; the line's pixels are the separator,
/// eliminated last, since no 4-neighbour pair crosses it; both sides are ordered the same way
/// first (on two cores when large). Sets of at most `leaf` pixels, or too thin to cut, keep
/// row-major order. Returns the order and the sizes of the two top-level halves.
fn nested_order(shape: &MaskShape, leaf: usize) -> Dissection {
    let mut order: Vec<u32> = (0..shape.len() as u32).collect();
    let halves = dissect(shape, &mut order, leaf.max(1));
    Dissection {
        order: order.into_iter().map(|v| v as usize).collect(),
        halves,
    }
}

/// Orders `cells` (unknowns, row-major on entry) in place as `[side 1, side 2, separator]`,
/// each side dissected again; the two side lengths when split.
fn dissect(shape: &MaskShape, cells: &mut [u32], leaf: usize) -> Option<[usize; 2]> {
    if cells.len() <= leaf {
        return None;
    }
    let at = |v: u32| shape.inside[v as usize];
    let (mut lo, mut hi) = ([u32::MAX; 2], [0u32; 2]);
    for &v in cells.iter() {
        let p = at(v);
        for a in 0..2 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let axis = usize::from(hi[1] - lo[1] > hi[0] - lo[0]);
    if hi[axis] - lo[axis] < 2 {
        return None;
    }
    // the median line by counting, kept strictly inside so that both sides are non-empty
    let mut count = vec![0usize; (hi[axis] - lo[axis] + 1) as usize];
    for &v in cells.iter() {
        count[(at(v)[axis] - lo[axis]) as usize] += 1;
    }
    let (mut cut, mut seen) = (0usize, 0usize);
    while seen + count[cut] < cells.len() / 2 {
        seen += count[cut];
        cut += 1;
    }
    let cut = lo[axis] + (cut as u32).clamp(1, hi[axis] - lo[axis] - 1);
    // stable three-way partition: before the line, after it, on it
    let mut parts: [Vec<u32>; 3] = Default::default();
    for &v in cells.iter() {
        let c = at(v)[axis];
        parts[if c < cut {
            0
        } else if c > cut {
            1
        } else {
            2
        }]
        .push(v);
    }
    let [n0, n1] = [parts[0].len(), parts[1].len()];
    let mut k = 0;
    for part in &parts {
        cells[k..k + part.len()].copy_from_slice(part);
        k += part.len();
    }
    drop(parts);
    let (first, rest) = cells.split_at_mut(n0);
    let second = &mut rest[..n1];
    if n0 + n1 >= PARALLEL_DISSECT {
        rayon::join(
            || dissect(shape, first, leaf),
            || dissect(shape, second, leaf),
        );
    } else {
        dissect(shape, first, leaf);
        dissect(shape, second, leaf);
    }
    Some([n0, n1])
}

/// Pixels from which the two sides of a dissection are ordered on two cores.
const PARALLEL_DISSECT: usize = 1 << 16;

/// The upper triangle of the Poisson matrix with the unknowns renumbered in `order` (the
/// `k`-th entry is the unknown eliminated `k`-th), in compressed columns: column `k` holds
/// the neighbours eliminated earlier (rows sorted), then the diagonal.
fn upper_in_order(shape: &MaskShape, order: &[usize]) -> SparseColMat<usize, f64> {
    let n = order.len();
    let mut pos = vec![0u32; n];
    for (k, &v) in order.iter().enumerate() {
        pos[v] = k as u32;
    }
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::with_capacity(3 * n);
    let mut values = Vec::with_capacity(3 * n);
    col_ptr.push(0usize);
    for (k, &v) in order.iter().enumerate() {
        let [x, y] = shape.inside[v];
        let mut rows = [0usize; 4];
        let mut m = 0;
        for (dx, dy) in [(-1, 0), (1, 0), (0, -1), (0, 1)] {
            if let Some(q) = shape.unknown(x as i64 + dx, y as i64 + dy) {
                let p = pos[q] as usize;
                if p < k {
                    rows[m] = p;
                    m += 1;
                }
            }
        }
        rows[..m].sort_unstable();
        for &r in &rows[..m] {
            row_idx.push(r);
            values.push(-1.0);
        }
        row_idx.push(k);
        values.push(4.0);
        col_ptr.push(row_idx.len());
    }
    let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
    SparseColMat::new(symbolic, values)
}

/// `A x` for the Poisson matrix of `shape`, every column of `x` (for residuals).
pub fn apply(shape: &MaskShape, x: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::zeros(x.nrows(), x.ncols());
    for_each_row(shape, x, |k, c, v| out[(k, c)] = v);
    out
}

/// `||b - A x||` (Frobenius over the columns), without forming `A x`; in parallel chunks.
pub fn residual_norm(shape: &MaskShape, x: MatRef<'_, f64>, b: MatRef<'_, f64>) -> f64 {
    if let Some([w, h]) = shape.rectangle() {
        return rect_residual_norm(w as usize, h as usize, x, b);
    }
    let n = shape.len();
    // the columns as slices (a copy for a strided one): plain indexing in the loop
    fn cols(m: MatRef<'_, f64>) -> Vec<std::borrow::Cow<'_, [f64]>> {
        m.col_iter()
            .map(|c| match c.try_as_col_major() {
                Some(c) => std::borrow::Cow::Borrowed(c.as_slice()),
                None => std::borrow::Cow::Owned(c.iter().copied().collect()),
            })
            .collect()
    }
    let (xs, bs) = (cols(x), cols(b));
    let sum: f64 = (0..n.div_ceil(UNKNOWNS_PER_TASK))
        .into_par_iter()
        .map(|t| {
            let mut sum = 0.0;
            for k in t * UNKNOWNS_PER_TASK..((t + 1) * UNKNOWNS_PER_TASK).min(n) {
                let nb = shape.neighbours(k);
                for (xc, bc) in xs.iter().zip(&bs) {
                    let mut v = 4.0 * xc[k];
                    for &q in &nb {
                        if q != u32::MAX {
                            v -= xc[q as usize];
                        }
                    }
                    let r = bc[k] - v;
                    sum += r * r;
                }
            }
            sum
        })
        .collect::<Vec<f64>>()
        .iter()
        .sum();
    // chunk sums added in order: the same bits on any number of threads
    sum.sqrt()
}

/// Unknowns per parallel task of the residual of an irregular Ω (the course mask's 14.9k
/// unknowns in four tasks).
const UNKNOWNS_PER_TASK: usize = 1 << 12;

/// `residual_norm` for a whole `w x h` rectangle: the stencil on row-major columns, without
/// looking up the numbering; rows in parallel.
fn rect_residual_norm(w: usize, h: usize, x: MatRef<'_, f64>, b: MatRef<'_, f64>) -> f64 {
    let sum: f64 = (0..x.ncols() * h)
        .into_par_iter()
        .with_min_len(16)
        .map(|cy| {
            let (c, y) = (cy / h, cy % h);
            let (xc, bc) = (x.col(c), b.col(c));
            let mut sum = 0.0;
            for i in y * w..(y + 1) * w {
                let mut v = 4.0 * xc[i];
                if i % w > 0 {
                    v -= xc[i - 1];
                }
                if i % w + 1 < w {
                    v -= xc[i + 1];
                }
                if y > 0 {
                    v -= xc[i - w];
                }
                if y + 1 < h {
                    v -= xc[i + w];
                }
                let r = bc[i] - v;
                sum += r * r;
            }
            sum
        })
        .collect::<Vec<f64>>()
        .iter()
        .sum();
    // row sums added in order: the same bits on any number of threads
    sum.sqrt()
}

/// Calls `f(k, c, (A x)[k, c])` for every unknown and column.
fn for_each_row(shape: &MaskShape, x: MatRef<'_, f64>, mut f: impl FnMut(usize, usize, f64)) {
    for (k, &[px, py]) in shape.inside.iter().enumerate() {
        let (px, py) = (px as i64, py as i64);
        let nb = [(1, 0), (-1, 0), (0, 1), (0, -1)].map(|(dx, dy)| shape.unknown(px + dx, py + dy));
        for c in 0..x.ncols() {
            let mut v = 4.0 * x[(k, c)];
            for q in nb.iter().flatten() {
                v -= x[(*q, c)];
            }
            f(k, c, v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A disc of radius `r` in a `w x w` mask, with a one-pixel channel cut out of it (so that
    /// Ω is irregular), and an isolated pixel in a corner (a second component).
    fn disc(w: u32, r: f64) -> MaskShape {
        let c = w as f64 / 2.0;
        let flags: Vec<bool> = (0..w * w)
            .map(|i| {
                let (x, y) = ((i % w) as f64 + 0.5 - c, (i / w) as f64 + 0.5 - c);
                (x * x + y * y < r * r && !(x.abs() < 1.0 && y > 3.0)) || i == w + 1
            })
            .collect();
        MaskShape::from_flags(w, w, &flags)
    }

    #[test]
    fn nested_order_is_a_permutation_whose_halves_do_not_touch() {
        let shape = disc(61, 28.0);
        let n = shape.len();
        let Dissection { order, halves } = nested_order(&shape, 16);
        let mut seen = order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..n).collect::<Vec<_>>());
        let [h0, h1] = halves.unwrap();
        assert!(h0 > n / 3 && h1 > n / 3, "{h0} {h1} of {n}");
        // no 4-neighbour pair joins the two halves (the separator is a whole grid line)
        let mut part = vec![2u8; n];
        for (k, &v) in order.iter().enumerate() {
            part[v] = if k < h0 {
                0
            } else if k < h0 + h1 {
                1
            } else {
                2
            };
        }
        for (v, &[x, y]) in shape.inside.iter().enumerate() {
            for (dx, dy) in [(1, 0), (0, 1)] {
                if let Some(q) = shape.unknown(x as i64 + dx, y as i64 + dy) {
                    assert!(part[v].max(part[q]) == 2 || part[v] == part[q], "{v} {q}");
                }
            }
        }
    }

    #[test]
    fn nested_dissection_factors_solve_like_amd() {
        let shape = disc(61, 28.0);
        let n = shape.len();
        let b = Mat::from_fn(n, 3, |i, j| ((i * 7 + j * 3) % 13) as f64 - 6.0);
        let mut reference = b.clone();
        factor(&shape).unwrap().solve_in_place(reference.as_mut());
        assert_eq!(factor(&shape).unwrap().ordering(), "amd");
        // one factor, then two domains (small threshold), twice each (kept scratch)
        for two_min in [usize::MAX, 100] {
            let f = factor_nested(&shape, 16, two_min).unwrap();
            assert_eq!(f.ordering(), "nested_dissection");
            assert_eq!(f.two_domains(), two_min == 100);
            for _ in 0..2 {
                let mut x = b.clone();
                f.solve_in_place(x.as_mut());
                let r = apply(&shape, x.as_ref()) - &b;
                assert!(r.norm_l2() < 1e-12 * b.norm_l2(), "{}", r.norm_l2());
                assert!((&x - &reference).norm_max() < 1e-12 * reference.norm_max());
            }
        }
    }

    #[test]
    fn matrix_entries_and_solve() {
        // an L of three pixels: (1,1) (2,1) (1,2)
        let mut flags = vec![false; 16];
        for i in [5, 6, 9] {
            flags[i] = true;
        }
        let shape = MaskShape::from_flags(4, 4, &flags);
        let a = poisson_matrix(&shape);
        let dense = a.to_dense();
        // lower triangle: 4 on the diagonal, -1 below for (2,1)-(1,1) and (1,2)-(1,1)
        assert_eq!(dense[(0, 0)], 4.0);
        assert_eq!(dense[(1, 0)], -1.0);
        assert_eq!(dense[(2, 0)], -1.0);
        assert_eq!(dense[(2, 1)], 0.0);
        let f = factor(&shape).unwrap();
        let b = Mat::from_fn(3, 2, |i, j| (i + 2 * j) as f64 + 1.0);
        let mut x = b.clone();
        f.solve_in_place(x.as_mut());
        let r = apply(&shape, x.as_ref()) - &b;
        assert!(r.norm_l2() < 1e-12 * b.norm_l2());
    }

    /// Timings of the reused course paste's stages on the course's images (not a check; run
    /// with `cargo test --release --lib course_solve_timing -- --ignored --nocapture`): the
    /// three-channel `solve3` against faer's solve of the three columns on one core, the
    /// right-hand sides and the residual (best of 200 each).
    #[test]
    #[ignore]
    fn course_solve_timing() {
        use cgnodes_formats::image_file::{decode_image, ColorSpace};
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/images/");
        let load = |name: &str, space| {
            decode_image(&std::fs::read(format!("{dir}{name}")).unwrap(), space).unwrap()
        };
        let shape = MaskShape::from_image(&load("BearInWater_mask.png", ColorSpace::Raw));
        let (target, source) = (
            load("NewBackGround.jpg", ColorSpace::Srgb),
            load("BearInWater.jpg", ColorSpace::Srgb),
        );
        let best = |f: &mut dyn FnMut()| {
            (0..200)
                .map(|_| {
                    let t = std::time::Instant::now();
                    f();
                    t.elapsed().as_secs_f64() * 1e3
                })
                .fold(f64::MAX, f64::min)
        };
        let f = factor(&shape).unwrap();
        let Kind::Amd(g) = &f.kind else {
            panic!("the course mask is factored by AMD")
        };
        let mut b = Mat::new();
        use super::super::{guidance::right_hand_side_into, Mode};
        for mode in [Mode::Seamless, Mode::Mixed] {
            let ms = best(&mut || {
                right_hand_side_into(&shape, &target, &source, [62, 162], mode, &mut b)
            });
            eprintln!("right-hand side, {mode:?}: {ms:.3} ms");
        }
        let (mut x, mut work) = (b.clone(), Vec::new());
        let ms = best(&mut || {
            x.copy_from(&b);
            assert!(g.solve3(x.as_mut(), &mut work));
        });
        eprintln!("solve3: {ms:.3} ms ({} factor entries)", g.factor_nnz());
        let ms = best(&mut || {
            x.copy_from(&b);
            g.solve_in_place(x.as_mut());
        });
        eprintln!("faer, three columns on one core: {ms:.3} ms");
        let ms = best(&mut || {
            std::hint::black_box(residual_norm(&shape, x.as_ref(), b.as_ref()));
        });
        eprintln!("residual: {ms:.3} ms");
    }
}
