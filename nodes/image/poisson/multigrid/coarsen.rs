//! Moving between levels: bilinear prolongation truncated to Ω, its transpose as restriction,
//! the Galerkin coarse operator `Pᵀ A P`, and the coarsest level's sparse Cholesky solve.

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
/// (`Pᵀ (-A u)` when `b` is `None`). The fine residual is formed row by row for the three
/// fine rows under each coarse row and never stored.
#[allow(clippy::needless_range_loop)] // xc is a grid coordinate, doubled for the fine rows
pub(super) fn restrict_residual(
    fine: &Level,
    coarse: &Level,
    u: &Field<f32>,
    b: Option<&Field<f32>>,
    bc: &mut Field<f32>,
) {
    let (mx, my) = ((fine.w - 1) / 2, (fine.h - 1) / 2);
    let (wf, wc) = (fine.w, coarse.w);
    for p in 0..2 {
        let f = |rows: &mut Vec<Q3>, (i, o): (usize, &mut [Q3])| {
            let yc = 2 * i + p;
            o.iter_mut().for_each(|v| *v = [0.0; 3]);
            if yc == 0 || yc >= my {
                return;
            }
            for (k, r) in rows.chunks_mut(wf).enumerate() {
                residual_row(fine, 2 * yc + k - 1, u, b, r);
            }
            let (r0, rest) = rows.split_at(wf);
            let (r1, r2) = rest.split_at(wf);
            for xc in 1..mx {
                if !coarse.inside(yc, xc) {
                    continue;
                }
                let x = 2 * xc;
                let mut s = [0.0f32; 3];
                for c in 0..3 {
                    // weights 1/2, 1, 1/2 along each axis (bilinear P, transposed)
                    let side = r0[x][c] + r2[x][c] + r1[x - 1][c] + r1[x + 1][c];
                    let corner = r0[x - 1][c] + r0[x + 1][c] + r2[x - 1][c] + r2[x + 1][c];
                    s[c] = r1[x][c] + 0.5 * side + 0.25 * corner;
                }
                o[xc] = s;
            }
        };
        let init = || vec![[0.0f32; 3]; 3 * wf];
        if coarse.par() {
            bc.rows[p]
                .par_chunks_mut(wc)
                .enumerate()
                .for_each_init(init, f);
        } else {
            let mut rows = init();
            bc.rows[p]
                .chunks_mut(wc)
                .enumerate()
                .for_each(|a| f(&mut rows, a));
        }
    }
}

/// `u += P uc` at the fine points inside.
#[allow(clippy::needless_range_loop)] // x indexes the row and, halved, the coarse rows
pub(super) fn prolong_add(fine: &Level, uc: &Field<f32>, u: &mut Field<f32>) {
    let (w, h) = (fine.w, fine.h);
    for p in 0..2 {
        for_rows(&mut u.rows[p], w, fine.par(), |i, o| {
            let y = 2 * i + p;
            if y == 0 || y + 1 >= h {
                return;
            }
            // the coarse rows this fine row interpolates from, with their weights
            // the coarse rows this fine row interpolates from (the same row twice for an even
            // y), so that a quarter of the four parents' sum is the bilinear value
            let (ra, rb) = (uc.row(y / 2), uc.row(y.div_ceil(2)));
            for x in 1..w - 1 {
                if !fine.inside(y, x) {
                    continue;
                }
                let (xa, xb) = (x / 2, x.div_ceil(2));
                for c in 0..3 {
                    o[x][c] += 0.25 * (ra[xa][c] + ra[xb][c] + rb[xa][c] + rb[xb][c]);
                }
            }
        });
    }
}

/// The coarse points whose bilinear basis function is non-zero at fine index `j` along one
/// axis, with its value there (one parent of weight 1 for an even `j`, two of 1/2 else).
pub(super) fn parents(j: usize) -> impl Iterator<Item = (usize, f64)> {
    let two = j % 2 == 1;
    [(j / 2, if two { 0.5 } else { 1.0 }), (j.div_ceil(2), 0.5)]
        .into_iter()
        .take(if two { 2 } else { 1 })
}

/// The Galerkin stencil `(Pᵀ A P)[I][·]` of coarse point `I = (yc, xc)`: for each fine point
/// `i` of its support, each fine neighbour `j` of `i` and each coarse parent `J` of `j`,
/// `A_c[I][J] += P[i][I] A[i][j] P[j][J]` (coarse points `0..=m` along each axis, the first
/// and last outside).
fn galerkin_at(fine: &Level, yc: usize, xc: usize, mx: usize, my: usize) -> [f64; 9] {
    let mut acc = [0.0f64; 9];
    for dy in 0..3 {
        let yi = 2 * yc + dy - 1;
        for dx in 0..3 {
            let xi = 2 * xc + dx - 1;
            if !fine.inside(yi, xi) {
                continue;
            }
            let wi = wt(dy as isize - 1) * wt(dx as isize - 1);
            for k in 0..9 {
                let aij = fine.coef(yi, xi, k);
                if aij == 0.0 {
                    continue;
                }
                let (yj, xj) = (yi + k / 3 - 1, xi + k % 3 - 1);
                for (yp, wy) in parents(yj) {
                    if yp == 0 || yp >= my {
                        continue;
                    }
                    for (xp, wx) in parents(xj) {
                        if xp == 0 || xp >= mx {
                            continue;
                        }
                        acc[(yp + 1 - yc) * 3 + (xp + 1 - xc)] += wi * aij * wy * wx;
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
    let probe = Level {
        w: 9,
        h: 9,
        op: match &fine.op {
            Op::Fine(_) => Op::Fine(probe_index.iter().map(|&i| i != 0).collect()),
            Op::Stencil { table, .. } => Op::Stencil {
                index: probe_index,
                table: table[..2].to_vec(),
            },
        },
        n: 49,
    };
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
    let rows: Vec<(Vec<u32>, Vec<[f64; 9]>)> = (0..h)
        .into_par_iter()
        .with_min_len(8)
        .map(|yc| {
            let (mut index, mut own) = (vec![0u32; w], Vec::new());
            if yc == 0 || yc >= my {
                return (index, own);
            }
            for xc in 1..mx {
                let (y, x) = (2 * yc, 2 * xc);
                let clear = yc >= 2 && yc + 2 <= my && xc >= 2 && xc + 2 <= mx;
                if clear && (y - 2..=y + 2).all(|yy| (x - 2..=x + 2).all(|xx| is_interior(yy, xx)))
                {
                    index[xc] = 1;
                    continue;
                }
                let s = galerkin_at(fine, yc, xc, mx, my);
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
    Level {
        w,
        h,
        op: Op::Stencil {
            index,
            table: table.iter().map(|s| s.map(|v| v as f32)).collect(),
        },
        n,
    }
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
            // the lower triangle: the diagonal, then the later neighbours (row-major)
            for k in 4..9 {
                let j = (y + k / 3 - 1) * w + x + k % 3 - 1;
                let a = level.coef(y, x, k);
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

    pub(super) fn solve(&self, b: &Field<f32>, u: &mut Field<f32>) {
        let w = b.w;
        let at = |g: usize| (g / w, g % w);
        let mut m = Mat::from_fn(self.cells.len(), 3, |k, c| {
            let (y, x) = at(self.cells[k]);
            f64::from(b.row(y)[x][c])
        });
        self.factor.solve_in_place(m.as_mut());
        u.fill_zero();
        for (k, &g) in self.cells.iter().enumerate() {
            let (y, x) = at(g);
            u.row_mut(y)[x] = [m[(k, 0)] as f32, m[(k, 1)] as f32, m[(k, 2)] as f32];
        }
    }
}
