//! Conjugate gradients' kernels on the fine level, in f64 (the search direction in f32, `A p`
//! formed exactly from it): the residual, `pᵀ A p`, the update of `x` and `r`, the dot
//! products of the flexible β, the next direction, and per-channel norms. Parallel sums add
//! per-row sums in row order, so the bits do not depend on the thread count.

use super::grid::*;
use super::*;

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
