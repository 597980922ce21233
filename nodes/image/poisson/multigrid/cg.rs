//! Conjugate gradients' kernels on the fine level, in f64 (the search direction in f32, `A p`
//! formed exactly from it): the residual, `pᵀ A p`, the update of `x` and `r`, the dot
//! products of the flexible β, the next direction, and per-channel norms. Sums are formed
//! per piece of `PIECE` points in four running lanes and added in piece order, so the bits
//! do not depend on the thread count.

use super::field::*;
use super::grid::*;
use super::*;

/// Per-channel sum.
pub(super) fn add3(s: P3, t: P3) -> P3 {
    [s[0] + t[0], s[1] + t[1], s[2] + t[2]]
}

/// Four running sums, one per SIMD lane, added at the end: a fixed order for a given
/// length, whatever the thread count.
#[inline(always)]
fn total(acc: [f64; 4]) -> f64 {
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// `s` as blocks of four values (each the same number of blocks as `n4`) and the rest.
#[inline(always)]
fn blocks<T>(s: &[T], n4: usize) -> (&[[T; 4]], &[T]) {
    let (a, b) = s.as_chunks::<4>();
    (&a[..n4], b)
}

/// `(A p)` at one point from f32 values (centre and left, right, up, down), in f64.
#[inline(always)]
fn ap1(c: f32, l: f32, r: f32, u: f32, d: f32) -> f64 {
    let f = f64::from;
    4.0 * f(c) - (f(l) + f(r)) - (f(u) + f(d))
}

/// `Σ w ∘ (A p)` over a run of points: `w` the weights (f32), `c` the centre values of `p`,
/// `nb` its four neighbours.
fn dot_ap(w: &[f32], c: &[f32], nb: [&[f32]; 4]) -> f64 {
    let n4 = c.len() / 4;
    let (w4, wt) = blocks(w, n4);
    let (c4, ct) = blocks(c, n4);
    let [(l4, lt), (r4, rt), (u4, ut), (d4, dt)] = nb.map(|s| blocks(s, n4));
    let mut acc = [0.0f64; 4];
    for j in 0..n4 {
        for k in 0..4 {
            acc[k] += f64::from(w4[j][k]) * ap1(c4[j][k], l4[j][k], r4[j][k], u4[j][k], d4[j][k]);
        }
    }
    for k in 0..ct.len() {
        acc[k] += f64::from(wt[k]) * ap1(ct[k], lt[k], rt[k], ut[k], dt[k]);
    }
    total(acc)
}

/// `Σ z ∘ r` over a run of points.
fn dot_zr(z: &[f32], r: &[f64]) -> f64 {
    let n4 = z.len() / 4;
    let ((z4, zt), (r4, rt)) = (blocks(z, n4), blocks(r, n4));
    let mut acc = [0.0f64; 4];
    for j in 0..n4 {
        for k in 0..4 {
            acc[k] += f64::from(z4[j][k]) * r4[j][k];
        }
    }
    for k in 0..zt.len() {
        acc[k] += f64::from(zt[k]) * rt[k];
    }
    total(acc)
}

/// `Σ v²` over a run of values.
fn dot_self(v: &[f64]) -> f64 {
    let n4 = v.len() / 4;
    let (v4, vt) = blocks(v, n4);
    let mut acc = [0.0f64; 4];
    for b in v4 {
        for k in 0..4 {
            acc[k] += b[k] * b[k];
        }
    }
    for (k, x) in vt.iter().enumerate() {
        acc[k] += x * x;
    }
    total(acc)
}

/// One channel's `x += α p`, `r -= α m ∘ (A p)`, `rhs = r` (f32) over a run of points;
/// returns `Σ r²`.
#[allow(clippy::too_many_arguments)]
fn update_run(
    x: &mut [f64],
    r: &mut [f64],
    rhs: &mut [f32],
    m: &[f32],
    c: &[f32],
    nb: [&[f32]; 4],
    a: f64,
) -> f64 {
    let n = c.len();
    let (x, r, rhs, m) = (&mut x[..n], &mut r[..n], &mut rhs[..n], &m[..n]);
    let [l, rt, u, d] = nb.map(|s| &s[..n]);
    for j in 0..n {
        x[j] += a * f64::from(c[j]);
        r[j] -= a * (f64::from(m[j]) * ap1(c[j], l[j], rt[j], u[j], d[j]));
        rhs[j] = r[j] as f32;
    }
    dot_self(r)
}

/// The pieces of a level's colours as (colour, first index, length), in `pieces` order.
fn spans(g: &Geom) -> Vec<(usize, usize, usize)> {
    let n2 = g.n2();
    (0..4)
        .flat_map(|c| {
            (0..n2)
                .step_by(PIECE)
                .map(move |lo| (c, lo, PIECE.min(n2 - lo)))
        })
        .collect()
}

/// The fine 5-point neighbours of colour `colour` at `i..i + n` in `f` (channel `ch`):
/// left, right, up, down.
#[inline(always)]
fn cross<'a, T>(
    g: &Geom,
    f: &'a [[Vec<T>; 3]; 4],
    colour: usize,
    ch: usize,
    i: usize,
    n: usize,
) -> [&'a [T]; 4] {
    let (x, y) = (&f[colour ^ 1][ch], &f[colour ^ 2][ch]);
    [
        at(x, i, g.offset(colour, 0, -1), n),
        at(x, i, g.offset(colour, 0, 1), n),
        at(y, i, g.offset(colour, -1, 0), n),
        at(y, i, g.offset(colour, 1, 0), n),
    ]
}

/// Conjugate gradients' `out = b - A u` (or `- A u` when `b` is `None`) for the fine 5-point
/// operator, zero outside Ω.
pub(super) fn fine_residual(
    level: &Level,
    lay: &Layout,
    u: &Field<f64>,
    b: Option<&Field<f64>>,
    out: &mut Field<f64>,
) {
    let g = level.g;
    run(pieces(&mut out.c), level.par(), |(colour, lo, out)| {
        let r = clip(&g, lo, out[0].len());
        if r.is_empty() {
            return;
        }
        let (i, n) = (lo + r.start, r.len());
        let m = &lay.mask[colour][i..i + n];
        for (ch, o) in out.into_iter().enumerate() {
            let o = &mut o[r.clone()];
            let c = &u.c[colour][ch][i..i + n];
            let [l, rr, up, dn] = cross(&g, &u.c, colour, ch, i, n);
            let bb = b.map(|b| &b.c[colour][ch][i..i + n]);
            for j in 0..n {
                let a = 4.0 * c[j] - (l[j] + rr[j]) - (up[j] + dn[j]);
                let v = bb.map_or(0.0, |bb| bb[j]) - a;
                o[j] = f64::from(m[j]) * v;
            }
        }
    });
}

/// Per channel `pᵀ A p` on the fine level (`p` zero outside Ω). `A p` is not stored: the
/// update recomputes it, which reads `p` (f32) instead of a stored f64 `A p`.
pub(super) fn p_ap(level: &Level, p: &Field<f32>) -> P3 {
    let g = level.g;
    run(spans(&g), level.par(), |(colour, lo, len)| {
        let r = clip(&g, lo, len);
        let (i, n) = (lo + r.start, r.len());
        std::array::from_fn(|ch| {
            if n == 0 {
                return 0.0;
            }
            let c = &p.c[colour][ch][i..i + n];
            let nb = cross(&g, &p.c, colour, ch, i, n);
            dot_ap(c, c, nb)
        })
    })
    .into_iter()
    .fold([0.0; 3], add3)
}

/// Conjugate gradients' update `x += α p`, `r -= α A p` (the search direction `p` in f32,
/// exact in f64, so `r` stays the residual of `x`), in one pass, also writing the new `r`
/// rounded to f32 into `rhs` (the V-cycle's right-hand side); returns `||r||²` per channel.
pub(super) fn cg_update(
    level: &Level,
    lay: &Layout,
    x: &mut Field<f64>,
    r: &mut Field<f64>,
    p: &Field<f32>,
    rhs: [&mut Grid; 3],
    alpha: P3,
) -> P3 {
    let g = level.g;
    let items: Vec<_> = pieces(&mut x.c)
        .into_iter()
        .zip(pieces(&mut r.c))
        .zip(grid_pieces(rhs))
        .collect();
    run(
        items,
        level.par(),
        |(((colour, lo, xs), (_, _, rs)), (_, _, bs))| {
            let span = clip(&g, lo, xs[0].len());
            let (i, n) = (lo + span.start, span.len());
            let mut s = [0.0; 3];
            if n == 0 {
                return s;
            }
            let m = &lay.mask[colour][i..i + n];
            for (ch, ((xo, ro), bo)) in xs.into_iter().zip(rs).zip(bs).enumerate() {
                let (xo, ro, bo) = (
                    &mut xo[span.clone()],
                    &mut ro[span.clone()],
                    &mut bo[span.clone()],
                );
                let c = &p.c[colour][ch][i..i + n];
                let nb = cross(&g, &p.c, colour, ch, i, n);
                s[ch] = update_run(xo, ro, bo, m, c, nb, alpha[ch]);
            }
            s
        },
    )
    .into_iter()
    .fold([0.0; 3], add3)
}

/// `out = a` rounded to f32 (the V-cycle's right-hand side from a residual).
pub(super) fn to_f32(level: &Level, a: &Field<f64>, out: [&mut Grid; 3]) {
    run(grid_pieces(out), level.par(), |(colour, lo, out)| {
        for (ch, o) in out.into_iter().enumerate() {
            let src = &a.c[colour][ch][lo..lo + o.len()];
            for (o, v) in o.iter_mut().zip(src) {
                *o = *v as f32;
            }
        }
    });
}

/// Per channel, `zᵀ r` and (with `p`) `zᵀ A p` in one pass: the preconditioned residual
/// against the residual and against the last step's `A p`, recomputed from `p` (zero
/// without `p`, the first step's). `z` is zero outside Ω.
pub(super) fn z_dots(
    level: &Level,
    z: [&Grid; 3],
    r: &Field<f64>,
    p: Option<&Field<f32>>,
) -> (P3, P3) {
    let g = level.g;
    run(spans(&g), level.par(), |(colour, lo, len)| {
        let span = clip(&g, lo, len);
        let (i, n) = (lo + span.start, span.len());
        let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
        if n == 0 {
            return (a, b);
        }
        for ch in 0..3 {
            let (zc, rc) = (&z[ch].c[colour][i..i + n], &r.c[colour][ch][i..i + n]);
            a[ch] = dot_zr(zc, rc);
            if let Some(p) = p {
                let c = &p.c[colour][ch][i..i + n];
                b[ch] = dot_ap(zc, c, cross(&g, &p.c, colour, ch, i, n));
            }
        }
        (a, b)
    })
    .into_iter()
    .fold(([0.0; 3], [0.0; 3]), |s, t| {
        (add3(s.0, t.0), add3(s.1, t.1))
    })
}

/// The new search direction `p = z + β ∘ p` per channel (rounded to f32).
pub(super) fn next_direction(level: &Level, p: &mut Field<f32>, z: [&Grid; 3], beta: P3) {
    run(pieces(&mut p.c), level.par(), |(colour, lo, out)| {
        for (ch, o) in out.into_iter().enumerate() {
            let src = &z[ch].c[colour][lo..lo + o.len()];
            let b = beta[ch];
            for (pv, zv) in o.iter_mut().zip(src) {
                *pv = (f64::from(*zv) + b * f64::from(*pv)) as f32;
            }
        }
    });
}

/// `x += z` (one plain V-cycle correction, for `vcycle_rate`).
pub(super) fn add_correction(x: &mut Field<f64>, z: [&Grid; 3]) {
    for (c, planes) in x.c.iter_mut().enumerate() {
        for (ch, xs) in planes.iter_mut().enumerate() {
            for (xv, zv) in xs.iter_mut().zip(&z[ch].c[c]) {
                *xv += f64::from(*zv);
            }
        }
    }
}

/// Per-channel squared norms of a field.
pub(super) fn norms(a: &Field<f64>) -> P3 {
    let par = 4 * a.g.n2() >= PAR_MIN;
    run(spans(&a.g), par, |(colour, lo, len)| {
        std::array::from_fn(|ch| {
            let v = &a.c[colour][ch][lo..lo + len];
            dot_self(v)
        })
    })
    .into_iter()
    .fold([0.0; 3], add3)
}
