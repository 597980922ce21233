//! Fast simulation of mass-spring systems (Liu, Bargteil, O'Brien & Kavan 2013), the
//! precursor of projective dynamics: backward Euler's objective
//! `1/(2h^2) (x-y)^T M (x-y) + sum_s 1/2 k_s |x_j - x_i - d_s|^2` minimized by block
//! coordinate descent over the positions `x` and the spring directions `d_s` with
//! `|d_s| = L_s` (their eq. 14):
//! - local step: `d_s = L_s (x_j - x_i) / |x_j - x_i|` (eq. 15),
//! - global step: `(M/h^2 + L) x = M y / h^2 + J d` (eq. 16), with `L = sum k_s A_s A_s^T`
//!   and `J = sum k_s A_s S_s^T`; the matrix is constant, so it is factored once (sparse
//!   Cholesky) and each iteration is two triangular solves for the three coordinates.
//!
//! Fixed vertices are eliminated (their coupling moves to the right-hand side). Collisions
//! with the sphere are resolved after the step as Liu et al. suggest for contact (their §5):
//! vertices inside the contact radius are projected onto it and lose their inward normal
//! velocity, so the prefactored matrix stays valid.

use super::springs::{axpy, dot, norm, scale, sub, Model, SetupError, Sphere, State};
use cgnodes_linalg::SpdFactor;
use faer::sparse::Triplet;
use faer::{Mat, Par};
use rayon::prelude::*;

/// The global matrix `M/h^2 + L` of Liu et al. 2013 (eq. 16) over the free vertices of `m`,
/// factored for many solves: each vertex's row (`None` when fixed), the number of free
/// vertices and the factor. Also the initial Hessian of the quasi-Newton integrator.
pub(super) fn global_factor(
    m: &Model,
    h: f64,
) -> Result<(Vec<Option<u32>>, usize, SpdFactor), SetupError> {
    let n = m.num_vertices();
    let (free, n_free) = m.free_indices();
    let mut t = Vec::new();
    for i in 0..n {
        if let Some(p) = free[i] {
            t.push(Triplet::new(p as usize, p as usize, m.mass[i] / (h * h)));
        }
    }
    for (s, e) in m.springs.ends.iter().enumerate() {
        let k = m.springs.k[s];
        let (fi, fj) = (free[e[0] as usize], free[e[1] as usize]);
        for p in [fi, fj].into_iter().flatten() {
            t.push(Triplet::new(p as usize, p as usize, k));
        }
        if let (Some(p), Some(q)) = (fi, fj) {
            let (p, q) = (p.max(q) as usize, p.min(q) as usize);
            t.push(Triplet::new(p, q, -k));
        }
    }
    // Small systems factor faster on one thread (and nodes already run in parallel).
    let par = if n_free >= 60_000 {
        Par::rayon(0)
    } else {
        Par::Seq
    };
    let mut factor = SpdFactor::new(n_free, &t, par).map_err(|e| {
        SetupError::NotPositiveDefinite(format!("the global matrix is not positive definite: {e}"))
    })?;
    factor.prepare_many_solves();
    Ok((free, n_free, factor))
}

/// The prefactored global matrix of Liu et al. 2013 for one model and time step.
pub struct Projective {
    free: Vec<Option<u32>>,
    n_free: usize,
    factor: SpdFactor,
    h: f64,
    /// Local/global iterations per step (Liu et al. use about 10).
    pub iterations: usize,
    d: Vec<[f64; 3]>,
}

impl Projective {
    /// Factors `M/h^2 + L` over the free vertices.
    pub fn new(m: &Model, h: f64, iterations: usize) -> Result<Projective, SetupError> {
        let (free, n_free, factor) = global_factor(m, h)?;
        Ok(Projective {
            free,
            n_free,
            factor,
            h,
            iterations: iterations.max(1),
            d: vec![[0.0; 3]; m.springs.len()],
        })
    }

    /// The time step the matrix was factored for.
    pub fn h(&self) -> f64 {
        self.h
    }

    /// Advances `st` by one step; returns the number of local/global iterations.
    pub fn step(&mut self, m: &Model, st: &mut State, sp: Option<&Sphere>) -> usize {
        let h = self.h;
        let n = m.num_vertices();
        let ih2 = 1.0 / (h * h);
        let y = m.inertial_positions(st, h);
        let mut x = y.clone();
        // Constant part of the right-hand side: M y / h^2.
        let mut b0 = Mat::<f64>::zeros(self.n_free, 3);
        for i in 0..n {
            if let Some(p) = self.free[i] {
                for c in 0..3 {
                    b0[(p as usize, c)] = m.mass[i] * ih2 * y[i][c];
                }
            }
        }
        for _ in 0..self.iterations {
            // Local step (eq. 15).
            let s = &m.springs;
            self.d
                .par_iter_mut()
                .enumerate()
                .with_min_len(8192)
                .for_each(|(i, d)| {
                    let [a, b] = s.ends[i];
                    let e = sub(x[b as usize], x[a as usize]);
                    let l = norm(e);
                    *d = if l > 0.0 {
                        scale(e, s.rest[i] / l)
                    } else {
                        [s.rest[i], 0.0, 0.0]
                    };
                });
            // Global step (eq. 16): b = M y/h^2 + J d (+ fixed-vertex coupling).
            let mut b = b0.clone();
            for (si, e) in s.ends.iter().enumerate() {
                let k = s.k[si];
                let (i, j) = (e[0] as usize, e[1] as usize);
                let d = self.d[si];
                match (self.free[i], self.free[j]) {
                    (Some(p), Some(q)) => {
                        for c in 0..3 {
                            b[(q as usize, c)] += k * d[c];
                            b[(p as usize, c)] -= k * d[c];
                        }
                    }
                    (Some(p), None) => {
                        for c in 0..3 {
                            b[(p as usize, c)] += k * (x[j][c] - d[c]);
                        }
                    }
                    (None, Some(q)) => {
                        for c in 0..3 {
                            b[(q as usize, c)] += k * (x[i][c] + d[c]);
                        }
                    }
                    (None, None) => {}
                }
            }
            self.factor.solve_in_place(b.as_mut());
            for i in 0..n {
                if let Some(p) = self.free[i] {
                    x[i] = [b[(p as usize, 0)], b[(p as usize, 1)], b[(p as usize, 2)]];
                }
            }
        }
        for i in 0..n {
            if self.free[i].is_none() {
                st.v[i] = [0.0; 3];
                continue;
            }
            let mut v = scale(sub(x[i], st.x[i]), m.damping / h);
            if let Some(spd) = sp {
                let r = spd.contact_radius();
                let d = sub(x[i], spd.center);
                let l = norm(d);
                if l < r && l > 0.0 {
                    let nn = scale(d, 1.0 / l);
                    x[i] = axpy(spd.center, r, nn);
                    let vn = dot(v, nn);
                    if vn < 0.0 {
                        v = axpy(v, -vn, nn);
                    }
                }
            }
            st.x[i] = x[i];
            st.v[i] = v;
        }
        self.iterations
    }
}
