//! The grid kernels of the multigrid hierarchy: a level's vectors (`Field`), its operator
//! (`Level`: the fine 5-point matrix or a Galerkin 9-point stencil), the four-colour
//! Gauss-Seidel sweeps, the residual and the conjugate-gradient update.

use super::*;

/// Three channels of one grid point.
pub(super) type P3 = [f64; 3];
/// Even rows and odd rows of a `w x h` grid of 3-channel values.
#[derive(Clone, Debug)]
pub(super) struct Field {
    pub(super) w: usize,
    pub(super) rows: [Vec<P3>; 2],
}

impl Field {
    pub(super) fn zeros(w: usize, h: usize) -> Field {
        Field {
            w,
            rows: [vec![[0.0; 3]; w * h.div_ceil(2)], vec![[0.0; 3]; w * (h / 2)]],
        }
    }

    pub(super) fn row(&self, y: usize) -> &[P3] {
        let i = (y >> 1) * self.w;
        &self.rows[y & 1][i..i + self.w]
    }

    pub(super) fn row_mut(&mut self, y: usize) -> &mut [P3] {
        let i = (y >> 1) * self.w;
        &mut self.rows[y & 1][i..i + self.w]
    }

    pub(super) fn fill_zero(&mut self) {
        for r in &mut self.rows {
            r.iter_mut().for_each(|v| *v = [0.0; 3]);
        }
    }
}

/// The operator of one level.
pub(super) enum Op {
    /// The fine 5-point matrix: which points are in Ω (the stencil is 4 u - Σ neighbours,
    /// whose outside values are zero).
    Fine(Vec<bool>),
    /// A Galerkin 9-point stencil per point, `[(dy + 1) * 3 + dx + 1]`; all zero outside.
    /// Stored in f32 (half the memory traffic of the coarse sweeps): the hierarchy is only a
    /// preconditioner, and the rounded stencils stay exactly symmetric (`galerkin`).
    Stencil(Vec<[f32; 9]>),
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
            Op::Stencil(a) => a[y * self.w + x][4] > 0.0,
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
            Op::Stencil(a) => f64::from(a[y * self.w + x][k]),
        }
    }

    /// `(A u)` at interior point `(y, x)` of `row`, reading the rows above and below.
    #[inline]
    pub(super) fn apply_at(&self, y: usize, x: usize, up: &[P3], row: &[P3], dn: &[P3]) -> P3 {
        match &self.op {
            Op::Fine(_) => {
                let mut v = [0.0; 3];
                for (c, v) in v.iter_mut().enumerate() {
                    *v = 4.0 * row[x][c] - row[x - 1][c] - row[x + 1][c] - up[x][c] - dn[x][c];
                }
                v
            }
            Op::Stencil(a) => {
                let s = a[y * self.w + x].map(f64::from);
                let mut v = [0.0; 3];
                for (c, v) in v.iter_mut().enumerate() {
                    *v = s[0] * up[x - 1][c]
                        + s[1] * up[x][c]
                        + s[2] * up[x + 1][c]
                        + s[3] * row[x - 1][c]
                        + s[4] * row[x][c]
                        + s[5] * row[x + 1][c]
                        + s[6] * dn[x - 1][c]
                        + s[7] * dn[x][c]
                        + s[8] * dn[x + 1][c];
                }
                v
            }
        }
    }
}

/// Runs `f(i, row)` over the `w`-wide rows of `rows`, in parallel when `par`.
pub(super) fn for_rows<F: Fn(usize, &mut [P3]) + Sync + Send>(rows: &mut [P3], w: usize, par: bool, f: F) {
    if par {
        rows.par_chunks_mut(w).enumerate().for_each(|(i, r)| f(i, r));
    } else {
        rows.chunks_mut(w).enumerate().for_each(|(i, r)| f(i, r));
    }
}

/// Gauss-Seidel over the rows with `y % 2 == py`: on each row the points with
/// `x % 2 == xs[0]`, then those with `x % 2 == xs[1]`. This is the colours `(xs[0], py)`
/// and `(xs[1], py)` one after the other (the second reads only its own row's first colour
/// and the other parity's rows, which neither changes), in one pass over the rows.
pub(super) fn smooth_rows(level: &Level, u: &mut Field, b: &Field, py: usize, xs: [usize; 2]) {
    let (w, h) = (level.w, level.h);
    let [r0, r1] = &mut u.rows;
    let (mine, other): (&mut [P3], &[P3]) = if py == 0 {
        (&mut r0[..], &r1[..])
    } else {
        (&mut r1[..], &r0[..])
    };
    for_rows(mine, w, level.par(), |i, row| {
        let y = 2 * i + py;
        if y == 0 || y + 1 >= h {
            return;
        }
        let up = &other[((y - 1) >> 1) * w..][..w];
        let dn = &other[((y + 1) >> 1) * w..][..w];
        let br = b.row(y);
        for px in xs {
            let x0 = if px == 0 { 2 } else { 1 };
            match &level.op {
                Op::Fine(m) => {
                    let m = &m[y * w..(y + 1) * w];
                    for x in (x0..w - 1).step_by(2) {
                        if m[x] {
                            for c in 0..3 {
                                row[x][c] = 0.25
                                    * (br[x][c]
                                        + row[x - 1][c]
                                        + row[x + 1][c]
                                        + up[x][c]
                                        + dn[x][c]);
                            }
                        }
                    }
                }
                Op::Stencil(a) => {
                    let a = &a[y * w..(y + 1) * w];
                    for x in (x0..w - 1).step_by(2) {
                        let s = a[x].map(f64::from);
                        if s[4] > 0.0 {
                            let inv = 1.0 / s[4];
                            for c in 0..3 {
                                let off = s[0] * up[x - 1][c]
                                    + s[1] * up[x][c]
                                    + s[2] * up[x + 1][c]
                                    + s[3] * row[x - 1][c]
                                    + s[5] * row[x + 1][c]
                                    + s[6] * dn[x - 1][c]
                                    + s[7] * dn[x][c]
                                    + s[8] * dn[x + 1][c];
                                row[x][c] = (br[x][c] - off) * inv;
                            }
                        }
                    }
                }
            }
        }
    });
}

/// The colours `(x % 2, y % 2)` in forward order, as row parity and the x parities on it
/// (the backward sweep runs them reversed: parity 1 then 0, on each row x parity 1 then 0).
pub(super) const COLOURS: [(usize, [usize; 2]); 2] = [(0, [0, 1]), (1, [0, 1])];

/// Runs `f(i, row)` over the `w`-wide rows of `rows` (in parallel when `par`), summing what
/// it returns.
pub(super) fn for_rows_sum<F: Fn(usize, &mut [P3]) -> P3 + Sync + Send>(
    rows: &mut [P3],
    w: usize,
    par: bool,
    f: F,
) -> P3 {
    let add = |s: P3, t: P3| [s[0] + t[0], s[1] + t[1], s[2] + t[2]];
    if par {
        rows.par_chunks_mut(w)
            .enumerate()
            .map(|(i, r)| f(i, r))
            .reduce(|| [0.0; 3], add)
    } else {
        rows.chunks_mut(w)
            .enumerate()
            .map(|(i, r)| f(i, r))
            .fold([0.0; 3], add)
    }
}

/// `out = b - A u` (or `A u` when `b` is `None`), zero outside Ω; returns the per-channel
/// dot product of `u` and `out` (conjugate gradients' `pᵀ A p`).
pub(super) fn residual(level: &Level, u: &Field, b: Option<&Field>, out: &mut Field) -> P3 {
    let (w, h) = (level.w, level.h);
    let mut dot = [0.0; 3];
    for p in 0..2 {
        let d = for_rows_sum(&mut out.rows[p], w, level.par(), |i, o| {
            let y = 2 * i + p;
            let mut d = [0.0; 3];
            if y == 0 || y + 1 >= h {
                o.iter_mut().for_each(|v| *v = [0.0; 3]);
                return d;
            }
            let (up, row, dn) = (u.row(y - 1), u.row(y), u.row(y + 1));
            o[0] = [0.0; 3];
            o[w - 1] = [0.0; 3];
            for x in 1..w - 1 {
                if !level.inside(y, x) {
                    o[x] = [0.0; 3];
                    continue;
                }
                let v = level.apply_at(y, x, up, row, dn);
                o[x] = match b {
                    Some(b) => {
                        let bv = b.row(y)[x];
                        [bv[0] - v[0], bv[1] - v[1], bv[2] - v[2]]
                    }
                    None => v,
                };
                for c in 0..3 {
                    d[c] += row[x][c] * o[x][c];
                }
            }
            d
        });
        dot = [dot[0] + d[0], dot[1] + d[1], dot[2] + d[2]];
    }
    dot
}

/// Matching chunks of `x`, `r`, `p`, `q` in `cg_update`.
pub(super) type CgChunks<'a> = (((&'a mut [P3], &'a mut [P3]), &'a [P3]), &'a [P3]);

/// Conjugate gradients' update `x += α p`, `r -= α q` in one pass; returns `||r||²` per
/// channel.
pub(super) fn cg_update(level: &Level, x: &mut Field, r: &mut Field, p: &Field, q: &Field, alpha: P3) -> P3 {
    let mut sum = [0.0; 3];
    for par in 0..2 {
        let f = |(((xv, rv), pv), qv): CgChunks<'_>| {
            let mut s = [0.0; 3];
            for i in 0..xv.len() {
                for c in 0..3 {
                    xv[i][c] += alpha[c] * pv[i][c];
                    rv[i][c] -= alpha[c] * qv[i][c];
                    s[c] += rv[i][c] * rv[i][c];
                }
            }
            s
        };
        let add = |s: P3, t: P3| [s[0] + t[0], s[1] + t[1], s[2] + t[2]];
        const CH: usize = 1 << 12;
        let (xr, rr) = (&mut x.rows[par], &mut r.rows[par]);
        let t = if level.par() {
            xr.par_chunks_mut(CH)
                .zip(rr.par_chunks_mut(CH))
                .zip(p.rows[par].par_chunks(CH))
                .zip(q.rows[par].par_chunks(CH))
                .map(f)
                .reduce(|| [0.0; 3], add)
        } else {
            xr.chunks_mut(CH)
                .zip(rr.chunks_mut(CH))
                .zip(p.rows[par].chunks(CH))
                .zip(q.rows[par].chunks(CH))
                .map(f)
                .fold([0.0; 3], add)
        };
        sum = add(sum, t);
    }
    sum
}
