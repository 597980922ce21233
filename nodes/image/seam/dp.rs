//! One vertical seam of minimal energy by dynamic programming (Avidan & Shamir 2007, eq. 4):
//! M(i, j) = e(i, j) + min(M(i-1, j-1), M(i-1, j), M(i-1, j+1)), then backtracking from the
//! smallest M in the last row. In forward mode (Rubinstein, Shamir & Avidan 2008, eq. 4)
//! each step costs the new neighbour differences the removal creates:
//! C_U = |I(i, j+1) - I(i, j-1)|, C_L = C_U + |I(i-1, j) - I(i, j-1)|,
//! C_R = C_U + |I(i-1, j) - I(i, j+1)|. Ties go to the leftmost candidate (numpy's argmin,
//! as the peer breaks them).

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

/// The minimal vertical seam of `g` (which must be at least one pixel wide).
pub fn find_seam(g: &Grid) -> Seam {
    let (w, h) = (g.w, g.h);
    let mut m = vec![0.0f64; w * h];
    let mut parent = vec![0u8; w * h]; // 0 = left, 1 = up, 2 = right
    let gray = &g.gray;
    let at = |x: isize, y: usize| gray[y * w + x.clamp(0, w as isize - 1) as usize];
    for (x, m0) in m.iter_mut().enumerate().take(w) {
        *m0 = g.mask[x]
            + match g.mode {
                Energy::Backward => g.energy[x],
                Energy::Forward => (at(x as isize + 1, 0) - at(x as isize - 1, 0)).abs(),
            };
    }
    for y in 1..h {
        let (prev, cur) = m.split_at_mut(y * w);
        let prev = &prev[(y - 1) * w..];
        let cur = &mut cur[..w];
        let par = &mut parent[y * w..(y + 1) * w];
        for x in 0..w {
            let (mut cl, mut cu, mut cr, base) = match g.mode {
                Energy::Backward => (0.0, 0.0, 0.0, g.energy[y * w + x]),
                Energy::Forward => {
                    let xi = x as isize;
                    let (l, r, up) = (at(xi - 1, y), at(xi + 1, y), at(xi, y - 1));
                    let c_u = (r - l).abs();
                    (c_u + (up - l).abs(), c_u, c_u + (up - r).abs(), 0.0)
                }
            };
            cl = if x > 0 { prev[x - 1] + cl } else { f64::INFINITY };
            cu += prev[x];
            cr = if x + 1 < w { prev[x + 1] + cr } else { f64::INFINITY };
            let (mut best, mut k) = (cl, 0u8);
            if cu < best {
                (best, k) = (cu, 1);
            }
            if cr < best {
                (best, k) = (cr, 2);
            }
            cur[x] = best + base + g.mask[y * w + x];
            par[x] = k;
        }
    }
    let last = &m[(h - 1) * w..];
    let mut x = 0;
    for (i, v) in last.iter().enumerate() {
        if *v < last[x] {
            x = i;
        }
    }
    let total = last[x];
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
