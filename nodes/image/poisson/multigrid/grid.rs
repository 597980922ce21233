//! The grid kernels of the multigrid hierarchy: a level's vectors (`Grid` per channel for the
//! V-cycle, `Field` of three channels for conjugate gradients), its operator (`Level`: the
//! fine 5-point matrix or a Galerkin 9-point stencil; `Layout`, the same by colour), the four-colour
//! Gauss-Seidel sweeps and the V-cycle's residual (all in f32: the V-cycle is only the
//! preconditioner). Conjugate gradients' fine-level kernels (f64) are in `cg.rs`.
//!
//! Vectors are stored by colour and channel: the grid points of one parity `(x % 2, y % 2)`
//! (a colour of the Gauss-Seidel sweep) form a grid of their own, one array per channel.
//! A colour's neighbours in x, in y and on the diagonals are then the other colours' arrays
//! at fixed offsets, so every kernel is a flat loop over contiguous arrays, which the
//! compiler turns into packed SIMD arithmetic (the points of one colour never depend on
//! each other).

use super::*;

/// Three channels of one grid point, for conjugate gradients (f64).
pub(super) type P3 = [f64; 3];

/// Where the points of a `w x h` level sit in the colour arrays: point `(y, x)` has colour
/// `(x & 1) + 2 (y & 1)` and index `((y + 1) >> 1) w2 + ((x + 1) >> 1)` in it. Each colour's
/// grid has a first and last row and column that hold no point inside Ω (the level's border
/// or no point at all), so the kernels run over `w2 + 1..n2 - w2 - 1` (`span`), where every
/// neighbour's index is in range and every point of Ω lies.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Geom {
    /// Width and height of each colour's grid.
    pub(super) w2: usize,
    pub(super) h2: usize,
}

impl Geom {
    pub(super) fn of(w: usize, h: usize) -> Geom {
        Geom {
            w2: (w + 3) / 2,
            h2: (h + 3) / 2,
        }
    }

    /// Points per colour.
    pub(super) fn n2(&self) -> usize {
        self.w2 * self.h2
    }

    /// Colour and index of point `(y, x)`.
    #[inline]
    pub(super) fn at(&self, y: usize, x: usize) -> (usize, usize) {
        (
            (x & 1) + 2 * (y & 1),
            ((y + 1) >> 1) * self.w2 + ((x + 1) >> 1),
        )
    }

    /// The indices every kernel visits: all neighbours in range, every point of Ω inside.
    pub(super) fn span(&self) -> std::ops::Range<usize> {
        let n2 = self.n2();
        (self.w2 + 1)..(n2.saturating_sub(self.w2 + 1)).max(self.w2 + 1)
    }

    /// Index offset from a point of colour `c` to its neighbour `(dy, dx)` (each -1, 0, 1),
    /// which has colour `c ^ (dx & 1) ^ 2 (dy & 1)`.
    #[inline]
    pub(super) fn offset(&self, c: usize, dy: isize, dx: isize) -> isize {
        let (px, py) = ((c & 1) as isize, (c >> 1) as isize);
        let h = match dx {
            -1 => -px,
            0 => 0,
            _ => 1 - px,
        };
        let v = match dy {
            -1 => -py,
            0 => 0,
            _ => 1 - py,
        };
        h + v * self.w2 as isize
    }
}

/// A level's vectors, three channels of each point: `c[colour][channel][index]` (`Geom`).
#[derive(Clone, Debug)]
pub(super) struct Field<T> {
    pub(super) g: Geom,
    pub(super) c: [[Vec<T>; 3]; 4],
}

/// Empties `r` for `n` values in its own memory, or in new memory when that is too small
/// (then a quarter more than asked, so that the next shape a little larger still fits the
/// written memory) or more than four times too large (so that a small shape does not hold a
/// large one's memory).
pub(super) fn fit<V>(r: &mut Vec<V>, n: usize) {
    r.clear();
    if r.capacity() > 4 * n.max(1024) {
        *r = Vec::new();
    }
    if r.capacity() < n {
        r.reserve_exact(n + n / 4);
    }
}

/// `r` with `n` values, stale or zero, in its own memory under `fit`'s rule.
pub(super) fn reshape<V: Copy + Default>(r: &mut Vec<V>, n: usize) {
    if r.capacity() < n || r.capacity() > 4 * n.max(1024) {
        fit(r, n);
    }
    r.resize(n, V::default());
}

impl<T: Copy + Default> Field<T> {
    /// No grid, no memory.
    pub(super) fn empty() -> Field<T> {
        Field {
            g: Geom::default(),
            c: Default::default(),
        }
    }

    pub(super) fn zeros(w: usize, h: usize) -> Field<T> {
        let mut f = Field::empty();
        f.reset(w, h);
        f
    }

    /// Zeros on a `w x h` grid, in the same allocations where they fit (`fit`).
    pub(super) fn reset(&mut self, w: usize, h: usize) {
        self.g = Geom::of(w, h);
        let n = self.g.n2();
        for r in self.c.iter_mut().flatten() {
            fit(r, n);
            r.resize(n, T::default());
        }
    }

    /// A copy of `src`, in the same allocations where it fits (`fit`; the derived
    /// `clone_from` would allocate anew).
    pub(super) fn assign(&mut self, src: &Field<T>) {
        self.g = src.g;
        for (r, s) in self.c.iter_mut().flatten().zip(src.c.iter().flatten()) {
            fit(r, s.len());
            r.extend_from_slice(s);
        }
    }

    /// Sets the three channels of point `(y, x)`.
    pub(super) fn set(&mut self, y: usize, x: usize, v: [T; 3]) {
        let (c, i) = self.g.at(y, x);
        for (ch, v) in v.into_iter().enumerate() {
            self.c[c][ch][i] = v;
        }
    }

    pub(super) fn fill_zero(&mut self) {
        for r in self.c.iter_mut().flatten() {
            r.fill(T::default());
        }
    }
}

/// One channel of a level's vector, by colour (`Geom`): the V-cycle runs each colour channel
/// on its own, the three in parallel.
#[derive(Clone, Debug, Default)]
pub(super) struct Grid {
    pub(super) g: Geom,
    pub(super) c: [Vec<f32>; 4],
}

impl Grid {
    pub(super) fn zeros(w: usize, h: usize) -> Grid {
        let mut f = Grid::default();
        f.reset(w, h);
        f
    }

    /// Zeros on a `w x h` grid, in the same allocations where they fit (`fit`).
    pub(super) fn reset(&mut self, w: usize, h: usize) {
        self.g = Geom::of(w, h);
        let n = self.g.n2();
        for r in &mut self.c {
            fit(r, n);
            r.resize(n, 0.0);
        }
    }

    /// A `w x h` grid of unspecified values, in the same allocations where they fit (`fit`),
    /// for vectors that every use writes in full before it reads them.
    pub(super) fn reshape(&mut self, w: usize, h: usize) {
        self.g = Geom::of(w, h);
        let n = self.g.n2();
        for r in &mut self.c {
            reshape(r, n);
        }
    }

    pub(super) fn get(&self, y: usize, x: usize) -> f32 {
        let (c, i) = self.g.at(y, x);
        self.c[c][i]
    }

    pub(super) fn set(&mut self, y: usize, x: usize, v: f32) {
        let (c, i) = self.g.at(y, x);
        self.c[c][i] = v;
    }

    pub(super) fn fill_zero(&mut self) {
        for r in &mut self.c {
            r.fill(0.0);
        }
    }
}

/// Three grids (one per channel) cut into pieces, as `pieces` cuts a field, in the same
/// order.
pub(super) fn grid_pieces<'a>(grids: [&'a mut Grid; 3]) -> Vec<Piece<'a, f32>> {
    let [a, b, c] = grids;
    let mut out = Vec::new();
    for (colour, ((a, b), c)) in a.c.iter_mut().zip(&mut b.c).zip(&mut c.c).enumerate() {
        colour_pieces([a, b, c], colour, &mut out);
    }
    out
}

/// One array cut into pieces of `PIECE` values: (first index, view).
pub(super) fn plane_pieces(v: &mut [f32]) -> Vec<(usize, &mut [f32])> {
    v.chunks_mut(PIECE)
        .enumerate()
        .map(|(k, o)| (k * PIECE, o))
        .collect()
}

/// A grid's colours cut into pieces of `PIECE` points: (colour, first index, view).
pub(super) fn pieces1(f: &mut Grid) -> Vec<(usize, usize, &mut [f32])> {
    let mut out = Vec::new();
    for (colour, v) in f.c.iter_mut().enumerate() {
        out.extend(plane_pieces(v).into_iter().map(|(lo, a)| (colour, lo, a)));
    }
    out
}

/// Points per parallel piece of a colour's array (fixed, so that sums over pieces are added
/// in the same order on any number of threads).
pub(super) const PIECE: usize = 2048;

/// One piece of work: colour, the index of its first point, and mutable views of the three
/// channels of one field over the piece's points.
pub(super) type Piece<'a, T> = (usize, usize, [&'a mut [T]; 3]);

/// Cuts the three channels of one colour into pieces of `PIECE` points (appended to `out`).
fn colour_pieces<'a, T>(planes: [&'a mut Vec<T>; 3], colour: usize, out: &mut Vec<Piece<'a, T>>) {
    let [a, b, c] = planes;
    let mut lo = 0;
    for ((a, b), c) in a
        .chunks_mut(PIECE)
        .zip(b.chunks_mut(PIECE))
        .zip(c.chunks_mut(PIECE))
    {
        let len = a.len();
        out.push((colour, lo, [a, b, c]));
        lo += len;
    }
}

/// Every colour of a field in pieces, colour by colour (fields of the same geometry give
/// the same pieces in the same order, so their pieces can be zipped).
pub(super) fn pieces<T>(f: &mut [[Vec<T>; 3]; 4]) -> Vec<Piece<'_, T>> {
    let mut out = Vec::new();
    for (c, planes) in f.iter_mut().enumerate() {
        colour_pieces(planes.each_mut(), c, &mut out);
    }
    out
}

/// Runs `f` on every item (in parallel when `par`) and returns its results in order.
pub(super) fn run<I: Send, R: Send>(
    items: Vec<I>,
    par: bool,
    f: impl Fn(I) -> R + Sync + Send,
) -> Vec<R> {
    if par {
        items.into_par_iter().map(f).collect()
    } else {
        items.into_iter().map(f).collect()
    }
}

/// The part `a..e` (relative to the piece) of a piece starting at `lo` of `len` points that
/// lies in the kernels' span.
#[inline]
pub(super) fn clip(g: &Geom, lo: usize, len: usize) -> std::ops::Range<usize> {
    let s = g.span();
    let a = s.start.max(lo).min(lo + len);
    let e = s.end.min(lo + len).max(a);
    (a - lo)..(e - lo)
}

/// `len` values of `plane` from index `i + off`.
#[inline(always)]
pub(super) fn at<T>(plane: &[T], i: usize, off: isize, len: usize) -> &[T] {
    &plane[(i as isize + off) as usize..][..len]
}

/// The operator of one level.
pub(super) enum Op {
    /// The fine 5-point matrix: which points are in Ω (the stencil is 4 u - Σ neighbours,
    /// whose outside values are zero).
    Fine(Vec<bool>),
    /// A Galerkin 9-point stencil per point, `[(dy + 1) * 3 + dx + 1]`, as an index per
    /// point into a table of stencils: entry 0 is all zero (outside), entry 1 the interior
    /// stencil that most points share, the others one per point near ∂Ω. Stored in f32 (the
    /// hierarchy is only a preconditioner); the rounded stencils stay exactly symmetric
    /// (`galerkin`).
    Stencil {
        index: Vec<u32>,
        table: Vec<[f32; 9]>,
    },
}

/// A 9-point level's stencils in the colour layout: `a[colour][k][index]` (zero outside Ω)
/// and the inverse of the diagonal (zero outside Ω), for the sweeps and the residual. All
/// nine couplings of a point are stored with it: reading the symmetric half from the
/// neighbours' entries instead (half the memory) made the course's first paste slower.
pub(super) struct Nine {
    pub(super) a: [[Vec<f32>; 9]; 4],
    pub(super) inv: [Vec<f32>; 4],
}

impl Nine {
    /// The coupling to neighbour `k` of the points `i..i + n` of colour `colour`.
    #[inline(always)]
    fn coef(&self, colour: usize, k: usize, i: usize, n: usize) -> &[f32] {
        &self.a[colour][k][i..i + n]
    }
}

/// One level of the hierarchy on its padded `w x h` grid (both odd; rows and columns 0 and
/// the last are always outside).
pub(super) struct Level {
    pub(super) w: usize,
    pub(super) h: usize,
    pub(super) op: Op,
    /// Unknowns of this level.
    pub(super) n: usize,
    /// The colour layout of its vectors.
    pub(super) g: Geom,
}

/// A level's operator in the colour layout, for the kernels: built into the work buffers
/// of a solve (`Layout::fill`, memory passed from solve to solve) rather than kept with the
/// hierarchy, so that a new shape's first paste writes it into pages already mapped.
#[derive(Default)]
pub(super) struct Layout {
    /// 1 inside Ω, 0 outside, per colour (`Geom`).
    pub(super) mask: [Vec<f32>; 4],
    /// The stencils per colour, for a 9-point level that is smoothed.
    pub(super) nine: Option<Nine>,
}

impl Layout {
    /// The layout of `level` (with `stencils`, its 9-point stencils per colour).
    #[cfg(test)]
    pub(super) fn of(level: &Level, stencils: bool) -> Layout {
        let mut l = Layout::default();
        l.fill(level, stencils);
        l
    }

    /// Fills the layout of `level` in this one's memory where it fits.
    pub(super) fn fill(&mut self, level: &Level, stencils: bool) {
        let (g, n2) = (level.g, level.g.n2());
        let zero = |v: &mut Vec<f32>| {
            fit(v, n2);
            v.resize(n2, 0.0);
        };
        self.mask.iter_mut().for_each(zero);
        match (&level.op, stencils) {
            (Op::Stencil { .. }, true) => {
                let nine = self.nine.get_or_insert_with(|| Nine {
                    a: Default::default(),
                    inv: Default::default(),
                });
                nine.a.iter_mut().flatten().for_each(zero);
                nine.inv.iter_mut().for_each(zero);
            }
            _ => self.nine = None,
        }
        for y in 1..level.h - 1 {
            for x in 1..level.w - 1 {
                if !level.inside(y, x) {
                    continue;
                }
                let (c, i) = g.at(y, x);
                self.mask[c][i] = 1.0;
                if let (Some(nine), Op::Stencil { index, table }) = (&mut self.nine, &level.op) {
                    let s = &table[index[y * level.w + x] as usize];
                    for (k, v) in s.iter().enumerate() {
                        nine.a[c][k][i] = *v;
                    }
                    nine.inv[c][i] = 1.0 / s[4];
                }
            }
        }
    }
}

impl Level {
    pub(super) fn new(w: usize, h: usize, op: Op, n: usize) -> Level {
        Level {
            w,
            h,
            op,
            n,
            g: Geom::of(w, h),
        }
    }

    pub(super) fn par(&self) -> bool {
        self.w * self.h >= PAR_MIN
    }

    pub(super) fn inside(&self, y: usize, x: usize) -> bool {
        match &self.op {
            Op::Fine(m) => m[y * self.w + x],
            Op::Stencil { index, .. } => index[y * self.w + x] != 0,
        }
    }

    /// The nine stencil coefficients of point `(y, x)` (all zero outside Ω).
    #[inline]
    pub(super) fn stencil(&self, y: usize, x: usize) -> [f64; 9] {
        match &self.op {
            Op::Fine(m) => {
                let i = y * self.w + x;
                let mut s = [0.0; 9];
                if m[i] {
                    s[4] = 4.0;
                    for (k, j) in [(1, i - self.w), (3, i - 1), (5, i + 1), (7, i + self.w)] {
                        if m[j] {
                            s[k] = -1.0;
                        }
                    }
                }
                s
            }
            Op::Stencil { index, table } => table[index[y * self.w + x] as usize].map(f64::from),
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

/// The neighbour `k` (9-point index, `(dy + 1) * 3 + dx + 1`) as `(dy, dx)`.
#[inline(always)]
pub(super) fn dir(k: usize) -> (isize, isize) {
    ((k / 3) as isize - 1, (k % 3) as isize - 1)
}

/// One Gauss-Seidel step on colour `colour` of `u`: every point of that colour set from its
/// neighbours (all other colours) and `b`. `first`: the first sweep from a zero start, which
/// reads no colour it has not written yet (`first_zero`: `u` holds stale values of any
/// shape, never cleared) and writes every value of its colour.
pub(super) fn smooth(
    level: &Level,
    lay: &Layout,
    u: &mut Grid,
    b: &Grid,
    colour: usize,
    first: bool,
) {
    let g = level.g;
    let zero = if first {
        first_zero(colour)
    } else {
        [false; 3]
    };
    let [c0, c1, c2, c3] = &mut u.c;
    let mut all = [Some(c0), Some(c1), Some(c2), Some(c3)];
    let mine = all[colour].take().expect("a colour");
    let other = all.map(|o| o.map(|v| &*v));
    let (ux, uy, ud) = (
        other[colour ^ 1].expect("x neighbours"),
        other[colour ^ 2].expect("y neighbours"),
        other[colour ^ 3].expect("diagonal neighbours"),
    );
    let (b, m) = (&b.c[colour], &lay.mask[colour]);
    run(plane_pieces(mine), level.par(), |(lo, o)| {
        let r = clip(&g, lo, o.len());
        if first {
            // the points outside the kernels' span stay zero (nothing else writes them)
            o[..r.start].fill(0.0);
            o[r.end..].fill(0.0);
        }
        if r.is_empty() {
            return;
        }
        let (i, n) = (lo + r.start, r.len());
        let o = &mut o[r];
        let (mm, bb) = (&m[i..i + n], &b[i..i + n]);
        let off = |k: usize| {
            let (dy, dx) = dir(k);
            g.offset(colour, dy, dx)
        };
        match &lay.nine {
            None => {
                let x = [at(ux, i, off(3), n), at(ux, i, off(5), n)];
                let y = [at(uy, i, off(1), n), at(uy, i, off(7), n)];
                fine_step(o, mm, bb, x, y, [zero[0], zero[1]]);
            }
            Some(nine) => {
                let inv = &nine.inv[colour][i..i + n];
                let a: [&[f32]; 9] = std::array::from_fn(|k| nine.coef(colour, k, i, n));
                let nb: [&[f32]; 9] = std::array::from_fn(|k| {
                    let src = match k {
                        4 => return bb,
                        3 | 5 => ux,
                        1 | 7 => uy,
                        _ => ud,
                    };
                    at(src, i, off(k), n)
                });
                nine_step(o, inv, bb, &a, &nb, zero);
            }
        }
    });
}

/// `o = m (b + x neighbours + y neighbours) / 4` (the fine level's Gauss-Seidel step),
/// leaving out the neighbour groups marked zero.
#[inline(always)]
fn fine_step(o: &mut [f32], m: &[f32], b: &[f32], x: [&[f32]; 2], y: [&[f32]; 2], zero: [bool; 2]) {
    let n = o.len();
    let (m, b) = (&m[..n], &b[..n]);
    let (l, r, u, d) = (&x[0][..n], &x[1][..n], &y[0][..n], &y[1][..n]);
    match zero {
        [false, false] => {
            for j in 0..n {
                o[j] = m[j] * (0.25 * (b[j] + (l[j] + r[j]) + (u[j] + d[j])));
            }
        }
        [false, true] => {
            for j in 0..n {
                o[j] = m[j] * (0.25 * (b[j] + (l[j] + r[j])));
            }
        }
        [true, false] => {
            for j in 0..n {
                o[j] = m[j] * (0.25 * (b[j] + (u[j] + d[j])));
            }
        }
        [true, true] => {
            for j in 0..n {
                o[j] = m[j] * (0.25 * b[j]);
            }
        }
    }
}

/// `o = inv (b - Σ_k a_k nb_k)` over the eight neighbours (a 9-point Gauss-Seidel step),
/// leaving out the neighbour groups marked zero (x, y, diagonal).
#[inline(always)]
fn nine_step(
    o: &mut [f32],
    inv: &[f32],
    b: &[f32],
    a: &[&[f32]; 9],
    nb: &[&[f32]; 9],
    zero: [bool; 3],
) {
    let n = o.len();
    let (inv, b) = (&inv[..n], &b[..n]);
    o.copy_from_slice(b);
    // x neighbours (3, 5), y neighbours (1, 7), diagonal (0, 2, 6, 8)
    for (group, ks) in [(0, [3, 5, 9, 9]), (1, [1, 7, 9, 9]), (2, [0, 2, 6, 8])] {
        if zero[group] {
            continue;
        }
        for k in ks {
            if k == 9 {
                continue;
            }
            let (ak, vk) = (&a[k][..n], &nb[k][..n]);
            for j in 0..n {
                o[j] -= ak[j] * vk[j];
            }
        }
    }
    for j in 0..n {
        o[j] *= inv[j];
    }
}

/// The colours in the forward order of a sweep (the backward sweep runs them reversed).
pub(super) const COLOURS: [usize; 4] = [0, 1, 2, 3];

/// The colours that are still zero when colour `c` is updated in the first forward sweep
/// from a zero start (x, y, diagonal neighbours): only colours updated before it are not.
pub(super) fn first_zero(c: usize) -> [bool; 3] {
    let done =
        |o: usize| COLOURS.iter().position(|&k| k == o) < COLOURS.iter().position(|&k| k == c);
    [!done(c ^ 1), !done(c ^ 2), !done(c ^ 3)]
}

/// `out = b - A u` (`- A u` when `b` is `None`) on every colour but `skip`, zero outside Ω.
pub(super) fn residual(
    level: &Level,
    lay: &Layout,
    u: &Grid,
    b: Option<&Grid>,
    skip: Option<usize>,
    out: &mut Grid,
) {
    let g = level.g;
    run(pieces1(out), level.par(), |(colour, lo, o)| {
        if skip == Some(colour) {
            return;
        }
        let r = clip(&g, lo, o.len());
        o[..r.start].fill(0.0);
        o[r.end..].fill(0.0);
        if r.is_empty() {
            return;
        }
        let (i, n) = (lo + r.start, r.len());
        let m = &lay.mask[colour][i..i + n];
        let o = &mut o[r];
        let nb: [&[f32]; 9] = std::array::from_fn(|k| {
            let (dy, dx) = dir(k);
            let c = colour ^ (dx & 1) as usize ^ (2 * (dy & 1)) as usize;
            at(&u.c[c], i, g.offset(colour, dy, dx), n)
        });
        match b {
            Some(b) => o.copy_from_slice(&b.c[colour][i..i + n]),
            None => o.fill(0.0),
        }
        match &lay.nine {
            None => {
                let (c, l, rr, up, dn) = (nb[4], nb[3], nb[5], nb[1], nb[7]);
                for j in 0..n {
                    o[j] = m[j] * (o[j] - (4.0 * c[j] - (l[j] + rr[j]) - (up[j] + dn[j])));
                }
            }
            Some(nine) => {
                for (k, vk) in nb.iter().enumerate() {
                    let ak = nine.coef(colour, k, i, n);
                    for j in 0..n {
                        o[j] -= ak[j] * vk[j];
                    }
                }
                for j in 0..n {
                    o[j] *= m[j];
                }
            }
        }
    });
}
