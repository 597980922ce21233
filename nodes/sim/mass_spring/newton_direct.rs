//! The Newton system of `implicit.rs` solved directly: the reduced Hessian `S^T H S` (free
//! vertices only) assembled into a fixed sparsity pattern built once per model, and factored
//! by faer's sparse Cholesky whose symbolic analysis (AMD ordering) is computed at the first
//! Newton step and reused by every later one; only the numeric factorization is redone.
//! Exact Newton steps; the reference for `newton_pcg.rs`, and its fallback.

use super::springs::{norm, spring_hessian_psd, sub, Model, Sphere};
use cgnodes_linalg::SpdFactor;
use faer::sparse::Triplet;
use faer::{MatMut, Par};

/// The reduced Hessian's pattern and values and its sparse Cholesky factor.
pub struct HessianCholesky {
    free: Vec<Option<u32>>,
    n_free: usize,
    /// The lower-triangle entries `(row, col)` of the reduced Hessian, in the order of `vals`.
    pattern: Vec<(usize, usize)>,
    /// The factor: analysed and factored at the first Newton step, then refactored with the
    /// same symbolic analysis at every later one.
    factor: Option<SpdFactor>,
    par: Par,
    /// Value slot of each spring's off-diagonal block (both ends free).
    spring_slot: Vec<Option<usize>>,
    vals: Vec<f64>,
    /// How many symbolic factorizations were computed.
    pub symbolic_count: usize,
    /// How many numeric factorizations were computed.
    pub numeric_count: usize,
}

impl HessianCholesky {
    /// Builds the reduced pattern `S^T H S`; the factor is analysed at the first `factor`.
    pub fn new(m: &Model) -> HessianCholesky {
        let (free, n_free) = m.free_indices();
        let mut idx: Vec<(usize, usize)> = Vec::new();
        // Diagonal 3x3 blocks, lower triangle (row >= col).
        for v in 0..n_free {
            for a in 0..3 {
                for b in 0..=a {
                    idx.push((3 * v + a, 3 * v + b));
                }
            }
        }
        let mut spring_slot = vec![None; m.springs.len()];
        for (s, e) in m.springs.ends.iter().enumerate() {
            if let (Some(p), Some(q)) = (free[e[0] as usize], free[e[1] as usize]) {
                if p == q {
                    continue;
                }
                let (p, q) = (p.max(q) as usize, p.min(q) as usize);
                spring_slot[s] = Some(idx.len());
                for a in 0..3 {
                    for b in 0..3 {
                        idx.push((3 * p + a, 3 * q + b));
                    }
                }
            }
        }
        // Small systems factor faster on one thread (and nodes already run in parallel).
        let par = if 3 * n_free >= 60_000 {
            Par::rayon(0)
        } else {
            Par::Seq
        };
        HessianCholesky {
            free,
            n_free,
            vals: vec![0.0; idx.len()],
            pattern: idx,
            factor: None,
            par,
            spring_slot,
            symbolic_count: 0,
            numeric_count: 0,
        }
    }

    /// Assembles the reduced Hessian of `g` at `x` (`ih2 = 1/h^2`) into the pattern's values.
    pub fn assemble(&mut self, m: &Model, x: &[[f64; 3]], ih2: f64, sp: Option<&Sphere>) {
        let n = m.num_vertices();
        self.vals.iter_mut().for_each(|v| *v = 0.0);
        for i in 0..n {
            if let Some(p) = self.free[i] {
                let base = 6 * p as usize;
                let mut c = 0;
                for a in 0..3 {
                    for b in 0..=a {
                        if a == b {
                            self.vals[base + c] += m.mass[i] * ih2;
                        }
                        c += 1;
                    }
                }
            }
        }
        for (s, e) in m.springs.ends.iter().enumerate() {
            let [i, j] = [e[0] as usize, e[1] as usize];
            let k = spring_hessian_psd(sub(x[j], x[i]), m.springs.rest[s], m.springs.k[s]);
            for v in [i, j] {
                if let Some(p) = self.free[v] {
                    add_lower(&mut self.vals[6 * p as usize..], &k, 1.0);
                }
            }
            if let Some(slot) = self.spring_slot[s] {
                for a in 0..3 {
                    for b in 0..3 {
                        self.vals[slot + 3 * a + b] -= k[a][b];
                    }
                }
            }
        }
        if let Some(spd) = sp {
            // Gauss-Newton (PSD) part of the penalty Hessian: k_p n n^T.
            let r = spd.contact_radius();
            for i in 0..n {
                if let Some(p) = self.free[i] {
                    let d = sub(x[i], spd.center);
                    let l = norm(d);
                    if l < r && l > 0.0 {
                        let nn = [d[0] / l, d[1] / l, d[2] / l];
                        let mut kb = [[0.0; 3]; 3];
                        for a in 0..3 {
                            for b in 0..3 {
                                kb[a][b] = spd.k * nn[a] * nn[b];
                            }
                        }
                        add_lower(&mut self.vals[6 * p as usize..], &kb, 1.0);
                    }
                }
            }
        }
    }

    /// Factors the assembled values (the symbolic analysis at the first call only).
    /// `Err` with faer's reason when the matrix is not positive definite.
    pub fn factor(&mut self) -> Result<(), DirectError> {
        let vals = &self.vals;
        match &mut self.factor {
            Some(f) => f
                .refactor_with(vals.len(), |k| vals[k], self.par)
                .map_err(DirectError::NotPositiveDefinite)?,
            None => {
                let lower: Vec<Triplet<usize, usize, f64>> = (self.pattern.iter())
                    .zip(vals)
                    .map(|(&(r, c), &v)| Triplet::new(r, c, v))
                    .collect();
                self.factor = Some(
                    SpdFactor::new(3 * self.n_free, &lower, self.par)
                        .map_err(DirectError::NotPositiveDefinite)?,
                );
                self.symbolic_count += 1;
            }
        }
        self.numeric_count += 1;
        Ok(())
    }

    /// Solves with the last factor: `rhs` has three entries per vertex (fixed vertices
    /// ignored), the solution is written over it (zero at fixed vertices).
    pub fn solve(&self, mut rhs: MatMut<'_, f64>) -> Result<(), DirectError> {
        let f = self.factor.as_ref().ok_or(DirectError::NotFactored)?;
        let mut reduced = faer::Mat::<f64>::zeros(3 * self.n_free, 1);
        for (v, p) in self.free.iter().enumerate() {
            if let Some(p) = p {
                for a in 0..3 {
                    reduced[(3 * *p as usize + a, 0)] = rhs[(3 * v + a, 0)];
                }
            }
        }
        f.solve_in_place(reduced.as_mut());
        for (v, p) in self.free.iter().enumerate() {
            for a in 0..3 {
                rhs[(3 * v + a, 0)] = match p {
                    Some(p) => reduced[(3 * *p as usize + a, 0)],
                    None => 0.0,
                };
            }
        }
        Ok(())
    }
}

/// Why the sparse Cholesky of the Hessian failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DirectError {
    /// The factorization failed (`SpdFactor`'s reason: not positive definite).
    #[error("{0}")]
    NotPositiveDefinite(String),
    /// `solve` was called before `factor`.
    #[error("solve before the first factorization")]
    NotFactored,
}

/// Adds `s * k` to a diagonal block stored as its lower triangle row by row
/// (`(0,0), (1,0), (1,1), (2,0), (2,1), (2,2)`).
fn add_lower(dst: &mut [f64], k: &[[f64; 3]; 3], s: f64) {
    let mut c = 0;
    for a in 0..3 {
        for b in 0..=a {
            dst[c] += s * k[a][b];
            c += 1;
        }
    }
}
