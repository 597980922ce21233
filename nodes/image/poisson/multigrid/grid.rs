//! The grid kernels of the multigrid hierarchy: a level's vectors (`Field`), its operator
//! (`Level`: the fine 5-point matrix or a Galerkin 9-point stencil), the four-colour
//! Gauss-Seidel sweeps and the V-cycle's residual (all in f32: the V-cycle is only the
//! preconditioner), and conjugate gradients' fine-level kernels in f64.

use super::*;

/// Three channels of one grid point, for conjugate gradients (f64).
pub(super) type P3 = [f64; 3];
/// Three channels of one grid point, for the V-cycle (f32: half the memory traffic and half
/// the fresh pages of f64; conjugate gradients keeps the accuracy in f64).
pub(super) type Q3 = [f32; 3];

/// Even rows and odd rows of a `w x h` grid of 3-channel values.
#[derive(Debug)]
pub(super) struct Field<T> {
    pub(super) w: usize,
    pub(super) rows: [Vec<[T; 3]>; 2],
}

impl<T: Copy> Clone for Field<T> {
    fn clone(&self) -> Self {
        Field {
            w: self.w,
            rows: self.rows.clone(),
        }
    }

    /// In `self`'s memory where it fits (the derived `clone_from` would allocate anew).
    fn clone_from(&mut self, source: &Self) {
        self.w = source.w;
        for (r, s) in self.rows.iter_mut().zip(&source.rows) {
            r.clone_from(s);
        }
    }
}

impl<T: Copy + Default> Field<T> {
    pub(super) fn zeros(w: usize, h: usize) -> Field<T> {
        let mut f = Field {
            w,
            rows: [Vec::new(), Vec::new()],
        };
        f.reset(w, h);
        f
    }

    /// Grid points held.
    pub(super) fn len(&self) -> usize {
        self.rows[0].len() + self.rows[1].len()
    }

    /// Grid points the allocations can hold.
    pub(super) fn capacity(&self) -> usize {
        self.rows[0].capacity() + self.rows[1].capacity()
    }

    /// Zeros on a `w x h` grid in the same allocations (new ones when those are too small,
    /// or more than four times too large, so that a small shape does not hold a large one's
    /// memory).
    pub(super) fn reset(&mut self, w: usize, h: usize) {
        let z = [T::default(); 3];
        self.w = w;
        for (r, n) in self.rows.iter_mut().zip([w * h.div_ceil(2), w * (h / 2)]) {
            r.clear();
            if r.capacity() > 4 * n.max(1024) {
                *r = Vec::new();
            }
            // a quarter more than asked when growing, so that the next shape a little larger
            // still fits the written memory
            if r.capacity() < n {
                r.reserve_exact(n + n / 4);
            }
            r.resize(n, z);
        }
    }

    pub(super) fn row(&self, y: usize) -> &[[T; 3]] {
        let i = (y >> 1) * self.w;
        &self.rows[y & 1][i..i + self.w]
    }

    pub(super) fn row_mut(&mut self, y: usize) -> &mut [[T; 3]] {
        let i = (y >> 1) * self.w;
        &mut self.rows[y & 1][i..i + self.w]
    }

    pub(super) fn fill_zero(&mut self) {
        for r in &mut self.rows {
            r.iter_mut().for_each(|v| *v = [T::default(); 3]);
        }
    }
}

/// The operator of one level.
pub(super) enum Op {
    /// The fine 5-point matrix: which points are in Ω (the stencil is 4 u - Σ neighbours,
    /// whose outside values are zero).
    Fine(Vec<bool>),
    /// A Galerkin 9-point stencil per point, `[(dy + 1) * 3 + dx + 1]`, as an index per
    /// point into a table of stencils: entry 0 is all zero (outside), entry 1 the interior
    /// stencil that most points share, the others one per point near ∂Ω. A sweep then reads
    /// 4 bytes per point instead of 36. Stored in f32 (the hierarchy is only a
    /// preconditioner); the rounded stencils stay exactly symmetric (`galerkin`).
    Stencil {
        index: Vec<u32>,
        table: Vec<[f32; 9]>,
    },
}

/// One level of the hierarchy on its padded `w x h` grid (both odd; rows and columns 0 and
/// the last are always outside).
pub(super) struct Level {
    pub(super) w: usize,
    pub(super) h: usize,
    pub(super) op: Op,
    /// Unknowns of this level.
    pub(super) n: usize,
}

impl Level {
    pub(super) fn par(&self) -> bool {
        self.w * self.h >= PAR_MIN
    }

    pub(super) fn inside(&self, y: usize, x: usize) -> bool {
        match &self.op {
            Op::Fine(m) => m[y * self.w + x],
            Op::Stencil { index, .. } => index[y * self.w + x] != 0,
        }
    }

    /// The stencil coefficient from point `(y, x)` to its neighbour `k` (9-point index).
    pub(super) fn coef(&self, y: usize, x: usize, k: usize) -> f64 {
        match &self.op {
            Op::Fine(m) => {
                let i = y * self.w + x;
                if !m[i] {
                    0.0
                } else if k == 4 {
                    4.0
                } else if k % 2 == 1 {
                    let j = (y + k / 3 - 1) * self.w + x + k % 3 - 1;
                    if m[j] {
                        -1.0
                    } else {
                        0.0
                    }
                } else {
                    0.0
                }
            }
            Op::Stencil { index, table } => f64::from(table[index[y * self.w + x] as usize][k]),
        }
    }
}

/// Runs `f(i, row)` over the `w`-wide rows of `rows`, in parallel when `par`.
pub(super) fn for_rows<T: Send, F: Fn(usize, &mut [T]) + Sync + Send>(
    rows: &mut [T],
    w: usize,
    par: bool,
    f: F,
) {
    if par {
        rows.par_chunks_mut(w)
            .enumerate()
            .for_each(|(i, r)| f(i, r));
    } else {
        rows.chunks_mut(w).enumerate().for_each(|(i, r)| f(i, r));
    }
}

/// Gauss-Seidel over the rows with `y % 2 == py`: on each row the points with
/// `x % 2 == xs[0]`, then those with `x % 2 == xs[1]`. This is the colours `(xs[0], py)`
/// and `(xs[1], py)` one after the other (the second reads only its own row's first colour
/// and the other parity's rows, which neither changes), in one pass over the rows.
///
/// `first`: the first sweep of a V-cycle, from a zero start. Every value this sweep has not
/// written yet is then read as zero (the other parity's rows on the even pass, the row's
/// second colour for its first), so `u` needs no clearing and the stale values are not read.
pub(super) fn smooth_rows(
    level: &Level,
    u: &mut Field<f32>,
    b: &Field<f32>,
    py: usize,
    xs: [usize; 2],
    first: bool,
) {
    let (w, h) = (level.w, level.h);
    let [r0, r1] = &mut u.rows;
    let (mine, other): (&mut [Q3], &[Q3]) = if py == 0 {
        (&mut r0[..], &r1[..])
    } else {
        (&mut r1[..], &r0[..])
    };
    // on the first sweep's even pass the odd rows are still zero
    let vertical = !(first && py == 0);
    let zero = [[0.0f32; 3]; 0];
    for_rows(mine, w, level.par(), |i, row| {
        let y = 2 * i + py;
        if y == 0 || y + 1 >= h {
            return;
        }
        let (up, dn): (&[Q3], &[Q3]) = if vertical {
            (
                &other[((y - 1) >> 1) * w..][..w],
                &other[((y + 1) >> 1) * w..][..w],
            )
        } else {
            (&zero, &zero)
        };
        let br = b.row(y);
        for (pass, px) in xs.into_iter().enumerate() {
            // the row's other colour is still zero for the first colour of a first sweep
            let across = !(first && pass == 0);
            let x0 = if px == 0 { 2 } else { 1 };
            match &level.op {
                Op::Fine(m) => {
                    let m = &m[y * w..(y + 1) * w];
                    for x in (x0..w - 1).step_by(2) {
                        if m[x] {
                            let mut s = br[x];
                            if across {
                                for c in 0..3 {
                                    s[c] += row[x - 1][c] + row[x + 1][c];
                                }
                            }
                            if vertical {
                                for c in 0..3 {
                                    s[c] += up[x][c] + dn[x][c];
                                }
                            }
                            row[x] = [0.25 * s[0], 0.25 * s[1], 0.25 * s[2]];
                        }
                    }
                }
                Op::Stencil { index, table } => {
                    let a = &index[y * w..(y + 1) * w];
                    for x in (x0..w - 1).step_by(2) {
                        if a[x] != 0 {
                            let s = &table[a[x] as usize];
                            let mut v = br[x];
                            if across {
                                for c in 0..3 {
                                    v[c] -= s[3] * row[x - 1][c] + s[5] * row[x + 1][c];
                                }
                            }
                            if vertical {
                                for (c, v) in v.iter_mut().enumerate() {
                                    *v -= off_rows(s, up, dn, x, c);
                                }
                            }
                            let inv = 1.0 / s[4];
                            row[x] = [v[0] * inv, v[1] * inv, v[2] * inv];
                        }
                    }
                }
            }
        }
    });
}

/// The six terms of a 9-point stencil `s` at `x` that read the rows above and below.
#[inline(always)]
fn off_rows(s: &[f32; 9], up: &[Q3], dn: &[Q3], x: usize, c: usize) -> f32 {
    s[0] * up[x - 1][c]
        + s[1] * up[x][c]
        + s[2] * up[x + 1][c]
        + s[6] * dn[x - 1][c]
        + s[7] * dn[x][c]
        + s[8] * dn[x + 1][c]
}

/// The colours `(x % 2, y % 2)` in forward order, as row parity and the x parities on it
/// (the backward sweep runs them reversed: parity 1 then 0, on each row x parity 1 then 0).
pub(super) const COLOURS: [(usize, [usize; 2]); 2] = [(0, [0, 1]), (1, [0, 1])];

/// Row `y` of `b - A u` (`- A u` when `b` is `None`) into `out`, zero outside Ω.
pub(super) fn residual_row(
    level: &Level,
    y: usize,
    u: &Field<f32>,
    b: Option<&Field<f32>>,
    out: &mut [Q3],
) {
    let (w, h) = (level.w, level.h);
    out.iter_mut().for_each(|v| *v = [0.0; 3]);
    if y == 0 || y + 1 >= h {
        return;
    }
    let (up, row, dn) = (u.row(y - 1), u.row(y), u.row(y + 1));
    let br = b.map(|b| b.row(y));
    let base = |x: usize| br.map_or([0.0; 3], |r| r[x]);
    match &level.op {
        Op::Fine(m) => {
            let m = &m[y * w..(y + 1) * w];
            for x in 1..w - 1 {
                if m[x] {
                    let mut v = base(x);
                    for c in 0..3 {
                        v[c] -=
                            4.0 * row[x][c] - row[x - 1][c] - row[x + 1][c] - up[x][c] - dn[x][c];
                    }
                    out[x] = v;
                }
            }
        }
        Op::Stencil { index, table } => {
            let a = &index[y * w..(y + 1) * w];
            for x in 1..w - 1 {
                if a[x] != 0 {
                    let s = &table[a[x] as usize];
                    let mut v = base(x);
                    for c in 0..3 {
                        v[c] -= off_rows(s, up, dn, x, c)
                            + s[3] * row[x - 1][c]
                            + s[4] * row[x][c]
                            + s[5] * row[x + 1][c];
                    }
                    out[x] = v;
                }
            }
        }
    }
}

/// Conjugate gradients' `out = b - A u` (or `A u` when `b` is `None`) for the fine 5-point
/// operator, zero outside Ω; returns the per-channel dot product of `u` and `out` (`pᵀ A p`).
pub(super) fn fine_residual(
    level: &Level,
    u: &Field<f64>,
    b: Option<&Field<f64>>,
    out: &mut Field<f64>,
) -> P3 {
    let (w, h) = (level.w, level.h);
    let Op::Fine(m) = &level.op else {
        unreachable!("conjugate gradients runs on the fine level")
    };
    let mut dot = [0.0; 3];
    for p in 0..2 {
        let d = for_rows_sum(&mut out.rows[p], w, level.par(), |i, o| {
            let y = 2 * i + p;
            let mut d = [0.0; 3];
            o.iter_mut().for_each(|v| *v = [0.0; 3]);
            if y == 0 || y + 1 >= h {
                return d;
            }
            let (up, row, dn) = (u.row(y - 1), u.row(y), u.row(y + 1));
            let m = &m[y * w..(y + 1) * w];
            for x in 1..w - 1 {
                if !m[x] {
                    continue;
                }
                let mut v = [0.0; 3];
                for c in 0..3 {
                    v[c] = 4.0 * row[x][c] - row[x - 1][c] - row[x + 1][c] - up[x][c] - dn[x][c];
                }
                if let Some(b) = b {
                    let bv = b.row(y)[x];
                    v = [bv[0] - v[0], bv[1] - v[1], bv[2] - v[2]];
                }
                o[x] = v;
                for c in 0..3 {
                    d[c] += row[x][c] * v[c];
                }
            }
            d
        });
        dot = add3(dot, d);
    }
    dot
}

/// Per-channel sum.
pub(super) fn add3(s: P3, t: P3) -> P3 {
    [s[0] + t[0], s[1] + t[1], s[2] + t[2]]
}

/// Runs `f(i, row)` over the `w`-wide rows of `rows` (in parallel when `par`), summing what
/// it returns.
pub(super) fn for_rows_sum<F: Fn(usize, &mut [P3]) -> P3 + Sync + Send>(
    rows: &mut [P3],
    w: usize,
    par: bool,
    f: F,
) -> P3 {
    if par {
        // per-row sums added in row order, as below: the same bits on any number of threads
        rows.par_chunks_mut(w)
            .enumerate()
            .map(|(i, r)| f(i, r))
            .collect::<Vec<_>>()
            .into_iter()
            .fold([0.0; 3], add3)
    } else {
        rows.chunks_mut(w)
            .enumerate()
            .map(|(i, r)| f(i, r))
            .fold([0.0; 3], add3)
    }
}

/// `(A p)` at inside point `x` of a fine row, from f32 values, in f64.
#[inline(always)]
fn fine_apply_at(up: &[Q3], row: &[Q3], dn: &[Q3], x: usize) -> P3 {
    let (l, c0, r, u, d) = (row[x - 1], row[x], row[x + 1], up[x], dn[x]);
    let mut a = [0.0; 3];
    for c in 0..3 {
        a[c] = 4.0 * f64::from(c0[c])
            - f64::from(l[c])
            - f64::from(r[c])
            - f64::from(u[c])
            - f64::from(d[c]);
    }
    a
}

/// Sums `f(y)` per channel over the interior rows `1..h - 1` (in parallel when `par`).
fn sum_rows(level: &Level, f: impl Fn(usize) -> (P3, P3) + Sync + Send) -> (P3, P3) {
    let add = |s: (P3, P3), t: (P3, P3)| (add3(s.0, t.0), add3(s.1, t.1));
    let zero = ([0.0; 3], [0.0; 3]);
    if level.par() {
        // per-row sums added in row order, as below: the same bits on any number of threads
        (1..level.h - 1)
            .into_par_iter()
            .map(f)
            .collect::<Vec<_>>()
            .into_iter()
            .fold(zero, add)
    } else {
        (1..level.h - 1).map(f).fold(zero, add)
    }
}

/// The fine level's inside flags.
fn fine_mask(level: &Level) -> &[bool] {
    match &level.op {
        Op::Fine(m) => m,
        Op::Stencil { .. } => unreachable!("conjugate gradients runs on the fine level"),
    }
}

/// Per channel `pᵀ A p` on the fine level (`p` zero outside Ω). `A p` is not stored: the
/// update recomputes it, which reads `p` (f32) instead of a stored f64 `A p`.
pub(super) fn p_ap(level: &Level, p: &Field<f32>) -> P3 {
    let (w, m) = (level.w, fine_mask(level));
    sum_rows(level, |y| {
        let (up, row, dn) = (p.row(y - 1), p.row(y), p.row(y + 1));
        let mut d = [0.0; 3];
        for x in 1..w - 1 {
            if m[y * w + x] {
                let a = fine_apply_at(up, row, dn, x);
                for c in 0..3 {
                    d[c] += f64::from(row[x][c]) * a[c];
                }
            }
        }
        (d, [0.0; 3])
    })
    .0
}

/// Conjugate gradients' update `x += α p`, `r -= α A p` (the search direction `p` in f32,
/// exact in f64, so `r` stays the residual of `x`), in one pass over the rows, also
/// writing the new `r` rounded to f32 into `rhs` (the V-cycle's right-hand side); returns
/// `||r||²` per channel.
pub(super) fn cg_update(
    level: &Level,
    x: &mut Field<f64>,
    r: &mut Field<f64>,
    p: &Field<f32>,
    rhs: &mut Field<f32>,
    alpha: P3,
) -> P3 {
    let (w, h, m) = (level.w, level.h, fine_mask(level));
    let mut sum = [0.0; 3];
    for par in 0..2 {
        type Rows<'a> = (usize, ((&'a mut [P3], &'a mut [P3]), &'a mut [Q3]));
        let f = |(i, ((xr, rr), br)): Rows<'_>| {
            let y = 2 * i + par;
            let mut s = [0.0; 3];
            if y == 0 || y + 1 >= h {
                return s;
            }
            let (up, row, dn) = (p.row(y - 1), p.row(y), p.row(y + 1));
            for xx in 1..w - 1 {
                if !m[y * w + xx] {
                    continue;
                }
                let a = fine_apply_at(up, row, dn, xx);
                for c in 0..3 {
                    xr[xx][c] += alpha[c] * f64::from(row[xx][c]);
                    rr[xx][c] -= alpha[c] * a[c];
                    s[c] += rr[xx][c] * rr[xx][c];
                    br[xx][c] = rr[xx][c] as f32;
                }
            }
            s
        };
        let (xr, rr, br) = (&mut x.rows[par], &mut r.rows[par], &mut rhs.rows[par]);
        let t = if level.par() {
            xr.par_chunks_mut(w)
                .zip(rr.par_chunks_mut(w))
                .zip(br.par_chunks_mut(w))
                .enumerate()
                .map(f)
                .collect::<Vec<_>>()
                .into_iter()
                .fold([0.0; 3], add3)
        } else {
            xr.chunks_mut(w)
                .zip(rr.chunks_mut(w))
                .zip(br.chunks_mut(w))
                .enumerate()
                .map(f)
                .fold([0.0; 3], add3)
        };
        sum = add3(sum, t);
    }
    sum
}

/// `out = a` rounded to f32 (the V-cycle's right-hand side from a residual).
pub(super) fn to_f32(level: &Level, a: &Field<f64>, out: &mut Field<f32>) {
    for p in 0..2 {
        let f = |(o, v): (&mut Q3, &P3)| *o = [v[0] as f32, v[1] as f32, v[2] as f32];
        if level.par() {
            out.rows[p]
                .par_iter_mut()
                .zip(a.rows[p].par_iter())
                .for_each(f);
        } else {
            out.rows[p].iter_mut().zip(a.rows[p].iter()).for_each(f);
        }
    }
}

/// Per channel, `zᵀ r` and (with `p`) `zᵀ A p` in one pass: the preconditioned residual
/// against the residual and against the last step's `A p`, recomputed from `p` (zero
/// without `p`, the first step's).
pub(super) fn z_dots(
    level: &Level,
    z: &Field<f32>,
    r: &Field<f64>,
    p: Option<&Field<f32>>,
) -> (P3, P3) {
    let (w, m) = (level.w, fine_mask(level));
    sum_rows(level, |y| {
        let (zr, rr) = (z.row(y), r.row(y));
        let rows = p.map(|p| (p.row(y - 1), p.row(y), p.row(y + 1)));
        let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
        for x in 1..w - 1 {
            if m[y * w + x] {
                for c in 0..3 {
                    a[c] += f64::from(zr[x][c]) * rr[x][c];
                }
                if let Some((up, row, dn)) = rows {
                    let ap = fine_apply_at(up, row, dn, x);
                    for c in 0..3 {
                        b[c] += f64::from(zr[x][c]) * ap[c];
                    }
                }
            }
        }
        (a, b)
    })
}

/// The new search direction `p = z + β ∘ p` per channel (rounded to f32).
pub(super) fn next_direction(level: &Level, p: &mut Field<f32>, z: &Field<f32>, beta: P3) {
    for r in 0..2 {
        let f = |(pv, zv): (&mut Q3, &Q3)| {
            for c in 0..3 {
                pv[c] = (f64::from(zv[c]) + beta[c] * f64::from(pv[c])) as f32;
            }
        };
        if level.par() {
            p.rows[r]
                .par_iter_mut()
                .zip(z.rows[r].par_iter())
                .for_each(f);
        } else {
            p.rows[r].iter_mut().zip(z.rows[r].iter()).for_each(f);
        }
    }
}

/// `x += z` (one plain V-cycle correction, for `vcycle_rate`).
pub(super) fn add_correction(x: &mut Field<f64>, z: &Field<f32>) {
    for r in 0..2 {
        for (xv, zv) in x.rows[r].iter_mut().zip(&z.rows[r]) {
            for c in 0..3 {
                xv[c] += f64::from(zv[c]);
            }
        }
    }
}

/// Per-channel squared norms of a field.
pub(super) fn norms(a: &Field<f64>) -> P3 {
    let sq = |x: &[P3]| {
        x.iter().fold([0.0; 3], |s, u| {
            [s[0] + u[0] * u[0], s[1] + u[1] * u[1], s[2] + u[2] * u[2]]
        })
    };
    // chunk sums added in chunk order whether the chunks ran in parallel or not: the same
    // bits on any number of threads
    const CHUNK: usize = 1 << 13;
    let mut s = [0.0; 3];
    for x in &a.rows {
        let parts: Vec<P3> = if x.len() >= PAR_MIN / 2 {
            x.par_chunks(CHUNK).map(sq).collect()
        } else {
            x.chunks(CHUNK).map(sq).collect()
        };
        s = parts.into_iter().fold(s, add3);
    }
    s
}
