//! Moving between levels: bilinear prolongation truncated to Ω, its transpose as restriction,
//! the Galerkin coarse operator `Pᵀ A P`, and the coarsest level's sparse Cholesky solve.

use super::field::*;
use super::grid::*;
use super::*;

/// Bilinear weight of offset `d` (-1, 0, 1) along one axis.
#[inline]
pub(super) fn wt(d: isize) -> f64 {
    if d == 0 {
        1.0
    } else {
        0.5
    }
}

/// `bc = Pᵀ (b - A u)` (full weighting times 4) at the coarse points inside, zero elsewhere
/// (`Pᵀ (-A u)` when `b` is `None`); the fine residual is formed in `r`. Coarse point `(yc,
/// xc)` sits on fine point `(2 yc, 2 xc)`, which is fine colour 0 at index `yc w2 + xc`, so
/// its 3 x 3 fine neighbourhood is at fixed offsets in the four fine colours: the
/// restriction is formed there for every coarse point at once (`plain`, fine colour 0's
/// grid), then sorted into the coarse colours. `relaxed`: `u` comes from a forward sweep,
/// whose last colour (3) saw no neighbour change after it was relaxed, so its residual is
/// zero (up to rounding) and is neither formed nor read.
#[allow(clippy::too_many_arguments)]
pub(super) fn restrict_residual(
    fine: &Level,
    coarse: &Level,
    lays: [&Layout; 2],
    u: &Grid,
    b: Option<&Grid>,
    relaxed: bool,
    r: &mut Grid,
    plain: &mut Vec<f32>,
    bc: &mut Grid,
) {
    let last = *COLOURS.last().expect("four colours");
    residual(fine, lays[0], u, b, relaxed.then_some(last), r);
    let (mx, my) = ((fine.w - 1) / 2, (fine.h - 1) / 2);
    let (g, gc) = (fine.g, coarse.g);
    let wf = g.w2;
    plain.resize(g.n2(), 0.0);
    let [r00, r10, r01, r11] = &r.c;
    run(plane_pieces(plain), fine.par(), |(lo, o)| {
        let s = clip(&g, lo, o.len());
        if s.is_empty() {
            return;
        }
        let (i, n) = (lo + s.start, s.len());
        let o = &mut o[s];
        let c = &r00[i..i + n];
        let (x0, x1) = (&r10[i..i + n], at(r10, i, 1, n));
        let (y0, y1) = (&r01[i..i + n], at(r01, i, wf as isize, n));
        // weights 1/2, 1, 1/2 along each axis (bilinear P, transposed)
        if relaxed {
            for j in 0..n {
                o[j] = c[j] + 0.5 * ((x0[j] + x1[j]) + (y0[j] + y1[j]));
            }
            return;
        }
        let (d0, d1, d2, d3) = (
            &r11[i..i + n],
            at(r11, i, 1, n),
            at(r11, i, wf as isize, n),
            at(r11, i, wf as isize + 1, n),
        );
        for j in 0..n {
            let side = (x0[j] + x1[j]) + (y0[j] + y1[j]);
            let corner = (d0[j] + d1[j]) + (d2[j] + d3[j]);
            o[j] = c[j] + 0.5 * side + 0.25 * corner;
        }
    });
    let plain = &*plain;
    run(pieces1(bc), coarse.par(), |(colour, lo, o)| {
        let (qx, qy) = (colour & 1, colour >> 1);
        let len = o.len();
        o.fill(0.0);
        let m = &lays[1].mask[colour];
        // the piece's rows of the coarse colour grid
        for yy in lo / gc.w2..(lo + len).div_ceil(gc.w2) {
            // coarse row 2 yy - qy, inside only for 1 <= yc < my
            let Some(yc) = (2 * yy).checked_sub(qy) else {
                continue;
            };
            if yc == 0 || yc >= my {
                continue;
            }
            let row = yy * gc.w2;
            // coarse columns xc = 2 xx - qx with 1 <= xc < mx
            let (xa, xe) = ((1 + qx).div_ceil(2), (mx + qx).div_ceil(2));
            let (a, e) = ((row + xa).max(lo), (row + xe).min(lo + len));
            if a >= e {
                continue;
            }
            let src = &plain[yc * wf..];
            for k in a..e {
                let xc = 2 * (k - row) - qx;
                o[k - lo] = m[k] * src[xc];
            }
        }
    });
}

/// `u += P uc` at the fine points inside. The coarse values are first laid out on fine
/// colour 0's grid (coarse point `(yc, xc)` at `yc w2 + xc`) in `plain`; each fine colour
/// then interpolates from fixed offsets in it.
pub(super) fn prolong_add(
    fine: &Level,
    coarse: &Level,
    lay: &Layout,
    uc: &Grid,
    plain: &mut Vec<f32>,
    u: &mut Grid,
) {
    let (mx, my) = ((fine.w - 1) / 2, (fine.h - 1) / 2);
    let (g, gc) = (fine.g, coarse.g);
    let wf = g.w2;
    // every entry the interpolation reads: coarse points 0..=m along each axis, zero past
    plain.resize(g.n2(), 0.0);
    for (yc, row) in plain.chunks_mut(wf).enumerate() {
        for (xc, v) in row.iter_mut().enumerate() {
            *v = if yc <= my && xc <= mx {
                let (c, i) = gc.at(yc, xc);
                uc.c[c][i]
            } else {
                0.0
            };
        }
    }
    let p = &*plain;
    run(pieces1(u), fine.par(), |(colour, lo, o)| {
        let r = clip(&g, lo, o.len());
        if r.is_empty() {
            return;
        }
        let (i, n) = (lo + r.start, r.len());
        let m = &lay.mask[colour][i..i + n];
        let o = &mut o[r];
        let c = &p[i..i + n];
        match colour {
            0 => {
                for j in 0..n {
                    o[j] += m[j] * c[j];
                }
            }
            1 | 2 => {
                let q = at(p, i, if colour == 1 { -1 } else { -(wf as isize) }, n);
                for j in 0..n {
                    o[j] += m[j] * (0.5 * (q[j] + c[j]));
                }
            }
            _ => {
                let (l, ul, u0) = (
                    at(p, i, -1, n),
                    at(p, i, -(wf as isize) - 1, n),
                    at(p, i, -(wf as isize), n),
                );
                for j in 0..n {
                    o[j] += m[j] * (0.25 * ((ul[j] + u0[j]) + (l[j] + c[j])));
                }
            }
        }
    });
}

/// The coarse parents of a fine point at offset `t` (-2..=2) from a coarse point's fine
/// position along one axis, as offsets from that coarse point with the bilinear weight: one
/// of weight 1 for an even `t`, two of 1/2 for an odd one (the second slot then unused).
const PARENTS: [[(isize, f64); 2]; 5] = [
    [(-1, 1.0), (0, 0.0)],
    [(-1, 0.5), (0, 0.5)],
    [(0, 1.0), (0, 0.0)],
    [(0, 0.5), (1, 0.5)],
    [(1, 1.0), (0, 0.0)],
];

/// The Galerkin stencil `(Pᵀ A P)[I][·]` of coarse point `I = (yc, xc)`: for each fine point
/// `i` of its support, each fine neighbour `j` of `i` and each coarse parent `J` of `j`,
/// `A_c[I][J] += P[i][I] A[i][j] P[j][J]` (coarse points `0..=m` along each axis, the first
/// and last outside).
fn galerkin_at(fine: &Level, yc: usize, xc: usize, mx: usize, my: usize) -> [f64; 9] {
    let mut acc = [0.0f64; 9];
    // which parent offsets are real coarse points (inside the padded range)
    let ok = |c: usize, d: isize, m: usize| {
        let p = c as isize + d;
        p > 0 && (p as usize) < m
    };
    for dy in 0..3 {
        let yi = 2 * yc + dy - 1;
        for dx in 0..3 {
            let xi = 2 * xc + dx - 1;
            let s = fine.stencil(yi, xi);
            if s[4] == 0.0 {
                continue;
            }
            let wi = wt(dy as isize - 1) * wt(dx as isize - 1);
            for (k, &a) in s.iter().enumerate() {
                if a == 0.0 {
                    continue;
                }
                // offsets of the neighbour j from I's fine position, then j's parents
                let (ty, tx) = (dy + k / 3, dx + k % 3);
                for &(py, wy) in &PARENTS[ty] {
                    if wy == 0.0 || !ok(yc, py, my) {
                        continue;
                    }
                    for &(px, wx) in &PARENTS[tx] {
                        if wx == 0.0 || !ok(xc, px, mx) {
                            continue;
                        }
                        acc[((py + 1) * 3 + px + 1) as usize] += wi * a * wy * wx;
                    }
                }
            }
        }
    }
    acc
}

/// The Galerkin coarse level `Pᵀ A P` of `fine` (Trottenberg et al. 2001, §2.3.2), point by
/// point (`galerkin_at`) near ∂Ω and once for the interior stencil that the points away from
/// it share.
#[allow(clippy::needless_range_loop)] // xc is a grid coordinate, doubled for the fine grid
pub(super) fn galerkin(fine: &Level) -> Level {
    let (mx, my) = ((fine.w - 1) / 2, (fine.h - 1) / 2);
    // coarse points 0..=m along each axis (0 and m outside), padded to an odd size
    let (w, h) = ((mx + 1) | 1, (my + 1) | 1);
    // a coarse point whose 5 x 5 fine block is all interior (inside Ω, and for a stencil
    // level sharing the interior stencil), with no neighbour on the border, has this level's
    // interior stencil: computed once, on a 9 x 9 probe of interior points
    let mut probe_index = vec![1u32; 81];
    for i in 0..9 {
        for j in [0, 8] {
            (probe_index[i * 9 + j], probe_index[j * 9 + i]) = (0, 0);
        }
    }
    let probe = Level::new(
        9,
        9,
        match &fine.op {
            Op::Fine(_) => Op::Fine(probe_index.iter().map(|&i| i != 0).collect()),
            Op::Stencil { table, .. } => Op::Stencil {
                index: probe_index,
                table: table[..2].to_vec(),
            },
        },
        49,
    );
    let mut interior = galerkin_at(&probe, 2, 2, 4, 4);
    for k in 5..9 {
        interior[k] = interior[8 - k];
    }
    let is_interior = |y: usize, x: usize| match &fine.op {
        Op::Fine(m) => m[y * fine.w + x],
        Op::Stencil { index, .. } => index[y * fine.w + x] == 1,
    };
    // per coarse row: the index of each point (1 interior, 0 outside, else 2 + the position
    // in the row's own list of stencils, renumbered below)
    // on the fine level a clear point's stencil depends only on which of the 5 x 5 fine
    // points around it are inside: points of the same pattern (along a smooth ∂Ω, most of
    // them) share one computation
    let fine_mask = match &fine.op {
        Op::Fine(m) => Some(m),
        Op::Stencil { .. } => None,
    };
    let pattern = |m: &[bool], y: usize, x: usize| {
        let mut key = 0u32;
        for yy in y - 2..=y + 2 {
            for &b in &m[yy * fine.w + x - 2..=yy * fine.w + x + 2] {
                key = key << 1 | u32::from(b);
            }
        }
        key
    };
    let rows: Vec<(Vec<u32>, Vec<[f64; 9]>)> = (0..h)
        .into_par_iter()
        .with_min_len(8)
        .map_init(std::collections::HashMap::new, |memo, yc| {
            let (mut index, mut own) = (vec![0u32; w], Vec::new());
            if yc == 0 || yc >= my {
                return (index, own);
            }
            for xc in 1..mx {
                let (y, x) = (2 * yc, 2 * xc);
                let clear = yc >= 2 && yc + 2 <= my && xc >= 2 && xc + 2 <= mx;
                let s = match (clear, fine_mask) {
                    (true, Some(m)) => {
                        let key = pattern(m, y, x);
                        if key == (1 << 25) - 1 {
                            index[xc] = 1;
                            continue;
                        }
                        *memo
                            .entry(key)
                            .or_insert_with(|| galerkin_at(fine, yc, xc, mx, my))
                    }
                    _ => {
                        if clear
                            && (y - 2..=y + 2)
                                .all(|yy| (x - 2..=x + 2).all(|xx| is_interior(yy, xx)))
                        {
                            index[xc] = 1;
                            continue;
                        }
                        galerkin_at(fine, yc, xc, mx, my)
                    }
                };
                if s[4] > 0.0 {
                    index[xc] = 2 + own.len() as u32;
                    own.push(s);
                }
            }
            (index, own)
        })
        .collect();
    let mut table = vec![[0.0f64; 9], interior];
    let mut index = Vec::with_capacity(w * h);
    for (row, own) in rows {
        let base = table.len() as u32 - 2;
        index.extend(row.into_iter().map(|i| if i >= 2 { i + base } else { i }));
        table.extend(own);
    }
    // exact symmetry: each coupling computed at both of its points may differ in the last
    // bit (summation order); the later point takes the earlier one's value, except that the
    // shared interior stencil (symmetric itself) is never changed: its partner takes its value
    for g in 0..index.len() {
        let ig = index[g] as usize;
        if ig == 0 {
            continue;
        }
        for k in 5..9 {
            let j = g + (k / 3) * w + k % 3 - w - 1;
            let ij = index.get(j).map_or(0, |&i| i as usize);
            match (ig, ij) {
                (_, 0) | (1, 1) => {}
                (_, 1) => table[ig][k] = interior[8 - k],
                _ => table[ij][8 - k] = table[ig][k],
            }
        }
    }
    let n = index.iter().filter(|&&i| i != 0).count();
    Level::new(
        w,
        h,
        Op::Stencil {
            index,
            table: table.iter().map(|s| s.map(|v| v as f32)).collect(),
        },
        n,
    )
}

/// The coarsest level's factor: its inside points numbered row-major and the sparse
/// Cholesky factor of its (slightly shifted) matrix.
pub(super) struct Coarsest {
    /// Grid index `y * w + x` of unknown `k`.
    pub(super) cells: Vec<usize>,
    pub(super) factor: SpdFactor,
}

impl Coarsest {
    pub(super) fn new(level: &Level) -> Result<Coarsest, PoissonError> {
        let w = level.w;
        let mut number = vec![usize::MAX; w * level.h];
        let mut cells = Vec::new();
        for y in 1..level.h - 1 {
            for x in 1..w - 1 {
                if level.inside(y, x) {
                    number[y * w + x] = cells.len();
                    cells.push(y * w + x);
                }
            }
        }
        let n = cells.len();
        let mut col_ptr = vec![0usize];
        let (mut row_idx, mut values) = (Vec::new(), Vec::new());
        for &g in &cells {
            let (y, x) = (g / w, g % w);
            let s = level.stencil(y, x);
            // the lower triangle: the diagonal, then the later neighbours (row-major)
            for (k, &a) in s.iter().enumerate().skip(4) {
                let j = (y + k / 3 - 1) * w + x + k % 3 - 1;
                if a == 0.0 || number[j] == usize::MAX {
                    continue;
                }
                row_idx.push(number[j]);
                values.push(if k == 4 { a * (1.0 + COARSE_SHIFT) } else { a });
            }
            col_ptr.push(row_idx.len());
        }
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let factor = SpdFactor::from_lower(SparseColMat::new(symbolic, values), None, Par::Seq)
            .map_err(|e| PoissonError::Factor(e.into()))?;
        Ok(Coarsest { cells, factor })
    }

    pub(super) fn solve(&self, level: &Level, b: &Grid, u: &mut Grid) {
        let w = level.w;
        let at = |g: usize| (g / w, g % w);
        let mut m = Mat::from_fn(self.cells.len(), 1, |k, _| {
            let (y, x) = at(self.cells[k]);
            f64::from(b.get(y, x))
        });
        self.factor.solve_in_place(m.as_mut());
        u.fill_zero();
        for (k, &g) in self.cells.iter().enumerate() {
            let (y, x) = at(g);
            u.set(y, x, m[(k, 0)] as f32);
        }
    }
}
