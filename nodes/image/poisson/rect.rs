//! A fast direct solver for the Poisson matrix of a rectangular Ω (the whole bounding box
//! inside), the matrix-decomposition method of Buzbee, Golub and Nielson (1970, "On direct
//! methods for solving Poisson's equations", §3), as in Hockney's FFT Poisson solvers.
//!
//! With Ω a `w x h` rectangle and unknowns numbered row-major, the matrix is
//! `A = T_w ⊗ I_h + I_w ⊗ T_h - ...`, the five-point stencil `4 u - Σ neighbours`. The sine
//! transform along a row (DST-I, `S_kn = sin(π k n / (w + 1))`) diagonalizes the row's
//! second difference: frequency `k` turns the stencil into the tridiagonal system
//! `a_k û_j - û_{j-1} - û_{j+1} = b̂_j` down the columns, with `a_k = 4 - 2 cos(π k / (w + 1))`.
//! So a solve is: a sine transform of every row, one tridiagonal solve per frequency,
//! an inverse sine transform of every row; O(w h log w) with no factor to store beyond the
//! tridiagonal pivots.
//!
//! The DST-I of a real row comes from one real FFT of length `w + 1` (see `sine_rows`).

use rayon::prelude::*;
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

/// Rows transformed per FFT batch (pairs of rows): keeps the batch in cache.
const PAIRS_PER_BATCH: usize = 16;

/// The solver for one rectangle size: the FFT plan and the tridiagonal pivots.
pub struct RectSolver {
    w: usize,
    h: usize,
    fft: Arc<dyn Fft<f64>>,
    /// `sin(π j / (w + 1))` for `j = 0..=w`.
    sin: Vec<f64>,
    /// `h x w` row-major: `1 / p_j(k)`, the reciprocal pivots of the tridiagonal elimination
    /// of frequency `k + 1` at row `j` (`p_0 = a_k`, `p_j = a_k - 1 / p_{j-1}`).
    inv_pivot: Vec<f64>,
}

impl RectSolver {
    /// The solver for a `w x h` rectangle of unknowns (both at least 1).
    pub fn new(w: usize, h: usize) -> RectSolver {
        let fft = FftPlanner::new().plan_fft_forward(w + 1);
        let sin = (0..=w)
            .map(|j| (std::f64::consts::PI * j as f64 / (w + 1) as f64).sin())
            .collect();
        let a: Vec<f64> = (1..=w)
            .map(|k| 4.0 - 2.0 * (std::f64::consts::PI * k as f64 / (w + 1) as f64).cos())
            .collect();
        let mut inv_pivot = vec![0.0; w * h];
        for j in 0..h {
            for k in 0..w {
                let p = if j == 0 {
                    a[k]
                } else {
                    a[k] - inv_pivot[(j - 1) * w + k]
                };
                inv_pivot[j * w + k] = 1.0 / p;
            }
        }
        RectSolver {
            w,
            h,
            fft,
            sin,
            inv_pivot,
        }
    }

    /// Number of unknowns.
    pub fn dim(&self) -> usize {
        self.w * self.h
    }

    /// Solves `A u = b` in place for one channel, `b` row-major (`h` rows of `w`).
    pub fn solve_in_place(&self, u: &mut [f64]) {
        debug_assert_eq!(u.len(), self.dim());
        self.sine_rows(u);
        self.tridiagonal(u);
        self.sine_rows(u);
        // the DST-I is its own inverse up to 2 / (w + 1)
        let s = 2.0 / (self.w + 1) as f64;
        u.iter_mut().for_each(|v| *v *= s);
    }

    /// The DST-I of every row of `u` in place: `F_k = Σ_n f_n sin(π k n / N)`, `N = w + 1`.
    ///
    /// Through one real FFT of length `N` per row (Press et al., "Numerical Recipes", §12.3,
    /// `sinft`): with `y_j = sin(π j / N) (f_j + f_{N-j}) + (f_j - f_{N-j}) / 2`, the FFT
    /// `Y_k = Σ_j y_j e^{-2π i j k / N}` gives `F_{2k} = -Im Y_k` and
    /// `F_{2k+1} = F_{2k-1} + Re Y_k` (`F_1 = Re Y_0 / 2`). Two rows share one complex FFT as
    /// its real and imaginary parts: `Y^a_k = (Z_k + conj Z_{N-k}) / 2`,
    /// `Y^b_k = (Z_k - conj Z_{N-k}) / 2i`.
    fn sine_rows(&self, u: &mut [f64]) {
        let n = self.w + 1;
        // batches are independent: one per task, each with its own buffers
        u.par_chunks_mut(2 * self.w * PAIRS_PER_BATCH)
            .for_each_init(
                || {
                    (
                        vec![Complex::new(0.0, 0.0); n * PAIRS_PER_BATCH],
                        vec![Complex::new(0.0, 0.0); self.fft.get_inplace_scratch_len()],
                    )
                },
                |(buf, scratch), rows| self.sine_batch(rows, buf, scratch),
            );
    }

    /// `sine_rows` for one batch of at most `2 PAIRS_PER_BATCH` rows.
    fn sine_batch(&self, rows: &mut [f64], buf: &mut [Complex<f64>], scratch: &mut [Complex<f64>]) {
        let (w, n) = (self.w, self.w + 1);
        {
            let pairs = rows.len().div_ceil(2 * w);
            let buf = &mut buf[..n * pairs];
            for (p, seq) in buf.chunks_mut(n).enumerate() {
                let a = &rows[2 * p * w..(2 * p + 1) * w];
                let b = rows.get((2 * p + 1) * w..(2 * p + 2) * w);
                seq[0] = Complex::new(0.0, 0.0);
                for j in 1..n {
                    // f_j = row[j - 1], f_{N-j} = row[w - j]
                    let y = |r: &[f64]| {
                        let (f, g) = (r[j - 1], r[w - j]);
                        self.sin[j] * (f + g) + 0.5 * (f - g)
                    };
                    seq[j] = Complex::new(y(a), b.map_or(0.0, y));
                }
            }
            self.fft.process_with_scratch(buf, scratch);
            for (p, seq) in buf.chunks(n).enumerate() {
                let (head, tail) = rows.split_at_mut((2 * p + 1) * w);
                let a = &mut head[2 * p * w..];
                let b = tail.get_mut(..w);
                let spectra = |k: usize| {
                    let (z, zc) = (seq[k], seq[(n - k) % n].conj());
                    let ya = (z + zc) * 0.5;
                    let yb = (z - zc) * Complex::new(0.0, -0.5);
                    (ya, yb)
                };
                let (y0a, y0b) = spectra(0);
                let (mut odd_a, mut odd_b) = (0.5 * y0a.re, 0.5 * y0b.re);
                a[0] = odd_a;
                let mut b = b;
                if let Some(b) = b.as_deref_mut() {
                    b[0] = odd_b;
                }
                for k in 1..=w / 2 {
                    let (ya, yb) = spectra(k);
                    // F_{2k} at index 2k - 1, F_{2k+1} at index 2k
                    a[2 * k - 1] = -ya.im;
                    odd_a += ya.re;
                    if 2 * k < w {
                        a[2 * k] = odd_a;
                    }
                    if let Some(b) = b.as_deref_mut() {
                        b[2 * k - 1] = -yb.im;
                        odd_b += yb.re;
                        if 2 * k < w {
                            b[2 * k] = odd_b;
                        }
                    }
                }
            }
        }
    }

    /// For every frequency (column of `u`), the tridiagonal solve down the rows.
    fn tridiagonal(&self, u: &mut [f64]) {
        let w = self.w;
        // forward elimination: g_j = (b_j + g_{j-1}) / p_j
        for j in 0..self.h {
            let (done, rest) = u.split_at_mut(j * w);
            let row = &mut rest[..w];
            let ip = &self.inv_pivot[j * w..(j + 1) * w];
            if j == 0 {
                row.iter_mut().zip(ip).for_each(|(v, &i)| *v *= i);
            } else {
                let prev = &done[(j - 1) * w..];
                for k in 0..w {
                    row[k] = (row[k] + prev[k]) * ip[k];
                }
            }
        }
        // back substitution: x_j = g_j + x_{j+1} / p_j
        for j in (0..self.h.saturating_sub(1)).rev() {
            let (head, tail) = u.split_at_mut((j + 1) * w);
            let row = &mut head[j * w..];
            let next = &tail[..w];
            let ip = &self.inv_pivot[j * w..(j + 1) * w];
            for k in 0..w {
                row[k] += next[k] * ip[k];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `A u` for the five-point stencil on a `w x h` rectangle with zero Dirichlet values.
    fn apply(w: usize, h: usize, u: &[f64]) -> Vec<f64> {
        let at = |x: i64, y: i64| {
            if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
                0.0
            } else {
                u[y as usize * w + x as usize]
            }
        };
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as i64, (i / w) as i64);
                4.0 * at(x, y) - at(x - 1, y) - at(x + 1, y) - at(x, y - 1) - at(x, y + 1)
            })
            .collect()
    }

    #[test]
    fn solves_the_five_point_system() {
        // odd and even row counts, a single row and a single column, prime widths
        for (w, h) in [
            (7, 5),
            (8, 6),
            (1, 1),
            (1, 9),
            (13, 1),
            (2, 3),
            (31, 17),
            (64, 33),
            (257, 130),
        ] {
            let b: Vec<f64> = (0..w * h).map(|i| ((i * 37 % 101) as f64) - 50.0).collect();
            let mut u = b.clone();
            RectSolver::new(w, h).solve_in_place(&mut u);
            let r = apply(w, h, &u);
            let err: f64 = r
                .iter()
                .zip(&b)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt();
            let bn: f64 = b.iter().map(|v| v * v).sum::<f64>().sqrt();
            assert!(err < 1e-12 * bn, "{w}x{h}: residual {err}");
        }
    }
}
