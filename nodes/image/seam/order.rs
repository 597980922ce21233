//! The optimal order of vertical and horizontal seam removals (Avidan & Shamir 2007, §3.3):
//! the transport map T(r, c) = min(T(r-1, c) + E(s_x(I_{n-r+1 x m-c})),
//! T(r, c-1) + E(s_y(I_{n-r x m-c+1}))), filled row by row while keeping the images of the
//! previous row, then backtracked into a sequence of removals.

use super::dp::find_seam;
use super::Grid;

/// Bytes the map may hold in intermediate grids before the caller falls back to width first.
pub const MEMORY_BUDGET: usize = 512 << 20;

/// Approximate bytes of the 2 (cols + 1) grids the map keeps for a `w x h` image.
pub fn memory_needed(w: usize, h: usize, cols: usize) -> usize {
    let per_pixel = 16 + 8 + 4 + 8 + 8;
    2 * (cols + 1) * w * h * per_pixel
}

/// Removes one horizontal seam from `g` (transposing there and back); returns its cost.
fn remove_horizontal(g: &mut Grid) -> f64 {
    g.transpose();
    let s = find_seam(g);
    g.remove_seam(&s.columns);
    g.transpose();
    s.cost
}

/// Removes one vertical seam; returns its cost.
fn remove_vertical(g: &mut Grid) -> f64 {
    let s = find_seam(g);
    g.remove_seam(&s.columns);
    s.cost
}

/// The order removing `rows` horizontal and `cols` vertical seams of least total cost (true
/// = a horizontal seam), and that total.
pub fn optimal_order(g: &Grid, rows: usize, cols: usize) -> (Vec<bool>, f64) {
    let width = cols + 1;
    let mut t = vec![0.0f64; (rows + 1) * width];
    let mut horizontal = vec![false; (rows + 1) * width];
    let mut prev: Vec<Grid> = Vec::new();
    for r in 0..=rows {
        let mut cur: Vec<Grid> = Vec::with_capacity(width);
        for c in 0..=cols {
            let i = r * width + c;
            if r == 0 && c == 0 {
                cur.push(g.clone());
                continue;
            }
            let mut best: Option<(f64, Grid, bool)> = None;
            if c > 0 {
                let mut a = cur[c - 1].clone();
                let cost = t[i - 1] + remove_vertical(&mut a);
                best = Some((cost, a, false));
            }
            if r > 0 {
                let mut a = prev[c].clone();
                let cost = t[i - width] + remove_horizontal(&mut a);
                // ties go to the vertical seam (width first)
                if best.as_ref().is_none_or(|b| cost < b.0) {
                    best = Some((cost, a, true));
                }
            }
            let (cost, grid, hz) = best.expect("r > 0 or c > 0");
            t[i] = cost;
            horizontal[i] = hz;
            cur.push(grid);
        }
        prev = cur;
    }
    let mut seq = Vec::with_capacity(rows + cols);
    let (mut r, mut c) = (rows, cols);
    while r > 0 || c > 0 {
        let hz = horizontal[r * width + c];
        seq.push(hz);
        if hz {
            r -= 1;
        } else {
            c -= 1;
        }
    }
    seq.reverse();
    (seq, t[rows * width + cols])
}
