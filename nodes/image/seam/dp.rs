//! One vertical seam of minimal energy by dynamic programming (Avidan & Shamir 2007, eq. 4):
//! M(i, j) = e(i, j) + min(M(i-1, j-1), M(i-1, j), M(i-1, j+1)), then backtracking from the
//! smallest M in the last row. In forward mode (Rubinstein, Shamir & Avidan 2008, eq. 4)
//! each step costs the new neighbour differences the removal creates:
//! C_U = |I(i, j+1) - I(i, j-1)|, C_L = C_U + |I(i-1, j) - I(i, j-1)|,
//! C_R = C_U + |I(i-1, j) - I(i, j+1)|. Ties go to the leftmost candidate (numpy's argmin,
//! as the peer breaks them). Only two rows of M are kept, and the choices (one byte each).

use super::{Energy, Grid};

/// The seam (one column per row) and its energy without the mask terms.
#[derive(Clone, Debug, PartialEq)]
pub struct Seam {
    /// Column of the seam in each row.
    pub columns: Vec<usize>,
    /// Sum of the energy along it (backward) or of the forward costs.
    pub energy: f64,
    /// The same with the mask terms: what the DP minimized.
    pub cost: f64,
}

/// The smallest of three candidates and which (0 = left, 1 = up, 2 = right), the leftmost on
/// ties.
#[inline(always)]
fn pick(cl: f64, cu: f64, cr: f64) -> (f64, u8) {
    let (mut best, mut k) = (cl, 0u8);
    if cu < best {
        (best, k) = (cu, 1);
    }
    if cr < best {
        (best, k) = (cr, 2);
    }
    (best, k)
}

/// One row of the backward DP: `cur[x] = e[x] + mask[x] + min of prev[x-1..=x+1]`.
fn backward_row(prev: &[f64], cur: &mut [f64], par: &mut [u8], e: &[f64], mask: &[f64]) {
    let w = cur.len();
    for x in 0..w {
        let cl = if x > 0 { prev[x - 1] } else { f64::INFINITY };
        let cr = if x + 1 < w {
            prev[x + 1]
        } else {
            f64::INFINITY
        };
        let (best, k) = pick(cl, prev[x], cr);
        cur[x] = best + e[x] + mask[x];
        par[x] = k;
    }
}

/// One row of the forward DP, rows `up` (i - 1) and `row` (i) of the gray image.
fn forward_row(
    prev: &[f64],
    cur: &mut [f64],
    par: &mut [u8],
    up: &[f64],
    row: &[f64],
    mask: &[f64],
) {
    let w = cur.len();
    for x in 0..w {
        // replicated borders: I(i, -1) = I(i, 0), I(i, w) = I(i, w - 1)
        let l = row[x.saturating_sub(1)];
        let r = row[(x + 1).min(w - 1)];
        let u = up[x];
        let c_u = (r - l).abs();
        let cl = if x > 0 {
            prev[x - 1] + c_u + (u - l).abs()
        } else {
            f64::INFINITY
        };
        let cr = if x + 1 < w {
            prev[x + 1] + c_u + (u - r).abs()
        } else {
            f64::INFINITY
        };
        let (best, k) = pick(cl, prev[x] + c_u, cr);
        cur[x] = best + mask[x];
        par[x] = k;
    }
}

/// The minimal vertical seam of `g` (which must be at least one pixel wide).
pub fn find_seam(g: &Grid) -> Seam {
    let (w, h) = (g.w, g.h);
    let mut parent = vec![0u8; w * h];
    let (mut prev, mut cur) = (vec![0.0f64; w], vec![0.0f64; w]);
    let gray = &g.gray;
    for (x, p) in prev.iter_mut().enumerate() {
        *p = g.mask[x]
            + match g.mode {
                Energy::Backward => g.energy[x],
                Energy::Forward => (gray[(x + 1).min(w - 1)] - gray[x.saturating_sub(1)]).abs(),
            };
    }
    for y in 1..h {
        let rows = y * w..(y + 1) * w;
        let par = &mut parent[rows.clone()];
        let mask = &g.mask[rows.clone()];
        match g.mode {
            Energy::Backward => backward_row(&prev, &mut cur, par, &g.energy[rows], mask),
            Energy::Forward => {
                let up = &gray[(y - 1) * w..y * w];
                forward_row(&prev, &mut cur, par, up, &gray[rows], mask)
            }
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    let mut x = 0;
    for (i, v) in prev.iter().enumerate() {
        if *v < prev[x] {
            x = i;
        }
    }
    let total = prev[x];
    let mut columns = vec![0; h];
    let mut mask_sum = 0.0;
    for y in (0..h).rev() {
        columns[y] = x;
        mask_sum += g.mask[y * w + x];
        if y > 0 {
            x = x + parent[y * w + x] as usize - 1;
        }
    }
    Seam {
        columns,
        energy: total - mask_sum,
        cost: total,
    }
}
