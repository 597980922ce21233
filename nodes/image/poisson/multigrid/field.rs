//! A level's vectors, stored by colour and channel: the grid points of one parity
//! `(x % 2, y % 2)` (a colour of the Gauss-Seidel sweep) form a grid of their own
//! (`Geom`), one array per channel (`Grid` for one channel of the V-cycle, `Field` of three
//! for conjugate gradients). A colour's neighbours in x, in y and on the diagonals are the
//! other colours' arrays at fixed offsets, so every kernel is a flat loop over contiguous
//! arrays, which the compiler turns into packed SIMD arithmetic. Also here: cutting the
//! arrays into the pieces that run in parallel (`pieces`, `run`).

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

/// `r` with `n` zeros, in its own memory under `fit`'s rule.
pub(super) fn zeroed<V: Copy + Default>(r: &mut Vec<V>, n: usize) {
    fit(r, n);
    r.resize(n, V::default());
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

    /// Zeros on a `w x h` grid, in the same allocations where they fit (`fit`).
    pub(super) fn reset(&mut self, w: usize, h: usize) {
        self.g = Geom::of(w, h);
        let n = self.g.n2();
        for r in self.c.iter_mut().flatten() {
            zeroed(r, n);
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
    /// Zeros on a `w x h` grid (new memory).
    #[cfg(test)]
    pub(super) fn zeros(w: usize, h: usize) -> Grid {
        let mut f = Grid::default();
        f.reshape(w, h);
        f
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
