//! The grid kernels of the multigrid hierarchy: a level's vectors (`Field`), its operator
//! (`Level`: the fine 5-point matrix or a Galerkin 9-point stencil), the four-colour
//! Gauss-Seidel sweeps and the V-cycle's residual (all in f32: the V-cycle is only the
//! preconditioner). Conjugate gradients' fine-level kernels (f64) are in `cg.rs`.

use super::*;

/// Three channels of one grid point, for conjugate gradients (f64).
pub(super) type P3 = [f64; 3];
/// Three channels of one grid point, for the V-cycle (f32: half the memory traffic and half
/// the fresh pages of f64; conjugate gradients keeps the accuracy in f64).
pub(super) type Q3 = [f32; 3];

/// Even rows and odd rows of a `w x h` grid of 3-channel values.
#[derive(Clone, Debug)]
pub(super) struct Field<T> {
    pub(super) w: usize,
    pub(super) rows: [Vec<[T; 3]>; 2],
}

/// Empties `r` for `n` values in its own memory, or in new memory when that is too small
/// (then a quarter more than asked, so that the next shape a little larger still fits the
/// written memory) or more than four times too large (so that a small shape does not hold a
/// large one's memory).
fn fit<V>(r: &mut Vec<V>, n: usize) {
    r.clear();
    if r.capacity() > 4 * n.max(1024) {
        *r = Vec::new();
    }
    if r.capacity() < n {
        r.reserve_exact(n + n / 4);
    }
}

impl<T: Copy + Default> Field<T> {
    /// No grid, no memory.
    pub(super) fn empty() -> Field<T> {
        Field {
            w: 0,
            rows: [Vec::new(), Vec::new()],
        }
    }

    pub(super) fn zeros(w: usize, h: usize) -> Field<T> {
        let mut f = Field::empty();
        f.reset(w, h);
        f
    }

    /// Zeros on a `w x h` grid, in the same allocations where they fit (`fit`).
    pub(super) fn reset(&mut self, w: usize, h: usize) {
        self.w = w;
        for (r, n) in self.rows.iter_mut().zip([w * h.div_ceil(2), w * (h / 2)]) {
            fit(r, n);
            r.resize(n, [T::default(); 3]);
        }
    }

    /// A copy of `src`, in the same allocations where it fits (`fit`; the derived
    /// `clone_from` would allocate anew).
    pub(super) fn assign(&mut self, src: &Field<T>) {
        self.w = src.w;
        for (r, s) in self.rows.iter_mut().zip(&src.rows) {
            fit(r, s.len());
            r.extend_from_slice(s);
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
