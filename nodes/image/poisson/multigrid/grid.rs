//! A level's operator (`Level`: the fine 5-point matrix or a Galerkin 9-point stencil;
//! `Layout`, the same by colour, `field.rs`), the four-colour Gauss-Seidel sweeps and the
//! V-cycle's residual, all in f32 (the V-cycle is only the preconditioner). Conjugate
//! gradients' fine-level kernels (f64) are in `cg.rs`.

use super::field::*;
use super::*;

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
        let zero = |v: &mut Vec<f32>| zeroed(v, n2);
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
