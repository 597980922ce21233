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

/// `bc = Pᵀ r` (full weighting times 4) at the coarse points inside, zero elsewhere.
pub(super) fn restrict(fine: &Level, coarse: &Level, r: &Field, bc: &mut Field) {
    let (mx, my) = ((fine.w - 1) / 2, (fine.h - 1) / 2);
    let wc = coarse.w;
    for p in 0..2 {
        for_rows(&mut bc.rows[p], wc, coarse.par(), |i, o| {
            let yc = 2 * i + p;
            o.iter_mut().for_each(|v| *v = [0.0; 3]);
            if yc == 0 || yc >= my {
                return;
            }
            let rows = [r.row(2 * yc - 1), r.row(2 * yc), r.row(2 * yc + 1)];
            for xc in 1..mx {
                if !coarse.inside(yc, xc) {
                    continue;
                }
                let mut s = [0.0; 3];
                for (dy, rr) in rows.iter().enumerate() {
                    let wy = wt(dy as isize - 1);
                    for dx in 0..3 {
                        let ww = wy * wt(dx as isize - 1);
                        let v = rr[2 * xc + dx - 1];
                        for c in 0..3 {
                            s[c] += ww * v[c];
                        }
                    }
                }
                o[xc] = s;
            }
        });
    }
}

/// `u += P uc` at the fine points inside.
#[allow(clippy::needless_range_loop)] // x indexes the row and, halved, the coarse rows
pub(super) fn prolong_add(fine: &Level, uc: &Field, u: &mut Field) {
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
                let ww = 0.25;
                for c in 0..3 {
                    o[x][c] += ww * (ra[xa][c] + ra[xb][c] + rb[xa][c] + rb[xb][c]);
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

/// The Galerkin coarse level `Pᵀ A P` of `fine` (Trottenberg et al. 2001, §2.3.2): for each
/// coarse point `I` and fine point `i` of its support, each fine neighbour `j` of `i` and each
/// coarse parent `J` of `j`, `A_c[I][J] += P[i][I] A[i][j] P[j][J]`.
#[allow(clippy::needless_range_loop)] // xc is a grid coordinate, doubled for the fine grid
pub(super) fn galerkin(fine: &Level) -> Level {
    let (mx, my) = ((fine.w - 1) / 2, (fine.h - 1) / 2);
    // coarse points 0..=m along each axis (0 and m outside), padded to an odd size
    let (w, h) = ((mx + 1) | 1, (my + 1) | 1);
    let mut a = vec![[0.0f64; 9]; w * h];
    a.par_chunks_mut(w)
        .enumerate()
        .with_min_len(8)
        .for_each(|(yc, out)| {
            if yc == 0 || yc >= my {
                return;
            }
            for xc in 1..mx {
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
                            // coarse parents of j and their weights
                            for (yp, wy) in parents(yj) {
                                if yp == 0 || yp >= my {
                                    continue;
                                }
                                for (xp, wx) in parents(xj) {
                                    if xp == 0 || xp >= mx {
                                        continue;
                                    }
                                    let kk = (yp + 1 - yc) * 3 + (xp + 1 - xc);
                                    acc[kk] += wi * aij * wy * wx;
                                }
                            }
                        }
                    }
                }
                out[xc] = acc;
            }
        });
    // exact symmetry: each coupling computed at both of its points may differ in the last
    // bit (summation order); the later point takes the earlier one's value
    for g in 0..a.len() {
        for k in 5..9 {
            let j = g + (k / 3) * w + k % 3 - w - 1;
            if j < a.len() {
                a[j][8 - k] = a[g][k];
            }
        }
    }
    let n = a.iter().filter(|s| s[4] > 0.0).count();
    Level {
        w,
        h,
        op: Op::Stencil(a.iter().map(|s| s.map(|v| v as f32)).collect()),
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
    pub(super) fn new(level: &Level) -> Result<Coarsest, String> {
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
        let factor = SpdFactor::from_lower(SparseColMat::new(symbolic, values), None, Par::Seq)?;
        Ok(Coarsest { cells, factor })
    }

    pub(super) fn solve(&self, b: &Field, u: &mut Field) {
        let w = b.w;
        let at = |g: usize| (g / w, g % w);
        let mut m = Mat::from_fn(self.cells.len(), 3, |k, c| {
            let (y, x) = at(self.cells[k]);
            b.row(y)[x][c]
        });
        self.factor.solve_in_place(m.as_mut());
        u.fill_zero();
        for (k, &g) in self.cells.iter().enumerate() {
            let (y, x) = at(g);
            u.row_mut(y)[x] = [m[(k, 0)], m[(k, 1)], m[(k, 2)]];
        }
    }
}
