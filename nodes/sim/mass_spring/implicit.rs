//! Backward (implicit) Euler as an optimization (Martin et al. 2011, "Example-based elastic
//! materials"; Gast et al. 2015, "Optimization integrator for large time steps"):
//!
//! `x_{n+1} = argmin_x g(x)`, `g(x) = 1/(2h^2) (x - y)^T M (x - y) + E(x)`,
//! `y = x_n + h v_n + h^2 g_ext`, `v_{n+1} = damping (x_{n+1} - x_n) / h`.
//!
//! Newton's method on `g` with the sparse Hessian `M/h^2 + sum_s K_s` where each spring's
//! 3x3 block is projected to be positive semi-definite (so the Newton direction always
//! descends), a backtracking line search with the Armijo condition, and fixed vertices
//! eliminated by the selection matrix `S` (unknowns are the free vertices only: the system
//! is `S^T H S dx = -S^T grad g`, Baraff & Witkin 1998 §5.3 in its reduced form). The sparse
//! Cholesky's symbolic analysis is computed once per model and reused by every Newton step of
//! every frame.

use super::springs::{
    add_collider_forces, axpy, collider_energy, dot, norm, spring_energy, spring_forces,
    spring_hessian_psd, sub, Incidence, Model, Sphere, State,
};
use crate::nodes::linalg::SpdFactor;
use faer::sparse::Triplet;
use faer::{Mat, Par};

/// Why a Newton step failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum NewtonError {
    /// The objective's gradient has a NaN or infinite entry (the state blew up).
    #[error("the gradient is not finite")]
    NonFiniteGradient,
    /// The Newton direction has a NaN or infinite entry.
    #[error("the Newton step is not finite")]
    NonFiniteStep,
    /// The sparse Cholesky factorization of the Hessian failed (`SpdFactor`'s reason).
    #[error("the Hessian is not positive definite: {0}")]
    NotPositiveDefinite(String),
}

/// Newton options.
#[derive(Clone, Copy, Debug)]
pub struct NewtonOptions {
    /// Most Newton iterations per step.
    pub max_iters: usize,
    /// Stop when the largest vertex move of a Newton step is below this (length units).
    pub tol: f64,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        NewtonOptions {
            max_iters: 20,
            tol: 1e-7,
        }
    }
}

/// The reduced sparsity pattern of the Hessian (built once per model) and its sparse Cholesky
/// factor (analysed once, at the first Newton step).
pub struct Implicit {
    /// Index of each vertex among the free ones (`None` when fixed).
    free: Vec<Option<u32>>,
    n_free: usize,
    /// The lower-triangle entries `(row, col)` of the reduced Hessian, in the order of `vals`.
    pattern: Vec<(usize, usize)>,
    /// The sparse Cholesky factor: analysed and factored at the first Newton step, then
    /// refactored with the same symbolic analysis (AMD ordering) at every later one.
    factor: Option<SpdFactor>,
    par: Par,
    /// Value slot of each spring's off-diagonal block (both ends free).
    spring_slot: Vec<Option<usize>>,
    vals: Vec<f64>,
    inc: Incidence,
    f: Vec<[f64; 3]>,
    /// Newton options.
    pub opts: NewtonOptions,
    /// How many symbolic factorizations were computed (0 before the first Newton step, then
    /// 1 for the life of the solver).
    pub symbolic_count: usize,
    /// How many numeric factorizations (= Newton steps) were computed.
    pub numeric_count: usize,
}

impl Implicit {
    /// Builds the reduced pattern `S^T H S`; the factor is analysed at the first Newton step.
    pub fn new(m: &Model, opts: NewtonOptions) -> Implicit {
        let n = m.num_vertices();
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
        let nd = 3 * n_free;
        // Small systems factor faster on one thread (and nodes already run in parallel).
        let par = if nd >= 60_000 {
            Par::rayon(0)
        } else {
            Par::Seq
        };
        Implicit {
            free,
            n_free,
            vals: vec![0.0; idx.len()],
            pattern: idx,
            factor: None,
            par,
            spring_slot,
            inc: Incidence::new(&m.springs, n),
            f: vec![[0.0; 3]; n],
            opts,
            symbolic_count: 0,
            numeric_count: 0,
        }
    }

    /// `g(x)` (without the constant part of fixed vertices).
    fn objective(
        &self,
        m: &Model,
        x: &[[f64; 3]],
        y: &[[f64; 3]],
        h: f64,
        sp: Option<&Sphere>,
    ) -> f64 {
        let mut inertia = 0.0;
        for i in 0..x.len() {
            if self.free[i].is_some() {
                let d = sub(x[i], y[i]);
                inertia += 0.5 * m.mass[i] * dot(d, d);
            }
        }
        inertia / (h * h) + spring_energy(&m.springs, x).0 + collider_energy(sp, x, &m.fixed)
    }

    /// Advances `st` by one backward Euler step; returns the number of Newton iterations.
    /// Fails when the Hessian is not positive definite (it cannot be with positive masses,
    /// unless values are not finite) or the state is not finite.
    pub fn step(
        &mut self,
        m: &Model,
        st: &mut State,
        h: f64,
        sp: Option<&Sphere>,
    ) -> Result<usize, NewtonError> {
        let n = m.num_vertices();
        let y = m.inertial_positions(st, h);
        // Initial guess: the inertial position y.
        let mut x: Vec<[f64; 3]> = y.clone();
        let ih2 = 1.0 / (h * h);
        let nd = 3 * self.n_free;
        let mut iters = 0;
        let mut g0 = self.objective(m, &x, &y, h, sp);
        for _ in 0..self.opts.max_iters {
            // Gradient of g over free vertices: M/h^2 (x - y) - f(x).
            self.f.resize(n, [0.0; 3]);
            spring_forces(&self.inc, &x, &mut self.f);
            add_collider_forces(sp, &x, &m.fixed, &mut self.f);
            let mut rhs = Mat::<f64>::zeros(nd, 1);
            let mut gmax = 0.0f64;
            for i in 0..n {
                if let Some(p) = self.free[i] {
                    let grad = axpy(
                        [-self.f[i][0], -self.f[i][1], -self.f[i][2]],
                        m.mass[i] * ih2,
                        sub(x[i], y[i]),
                    );
                    for a in 0..3 {
                        rhs[(3 * p as usize + a, 0)] = -grad[a];
                        gmax = gmax.max(grad[a].abs());
                    }
                }
            }
            if !gmax.is_finite() {
                return Err(NewtonError::NonFiniteGradient);
            }
            if gmax == 0.0 {
                break;
            }
            // Hessian values in the pattern's order.
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
            let vals = &self.vals;
            let factor = match &mut self.factor {
                Some(f) => {
                    f.refactor_with(vals.len(), |k| vals[k], self.par)
                        .map_err(NewtonError::NotPositiveDefinite)?;
                    f
                }
                None => {
                    let lower: Vec<Triplet<usize, usize, f64>> = (self.pattern.iter())
                        .zip(vals)
                        .map(|(&(r, c), &v)| Triplet::new(r, c, v))
                        .collect();
                    let f = SpdFactor::new(nd, &lower, self.par)
                        .map_err(NewtonError::NotPositiveDefinite)?;
                    self.symbolic_count += 1;
                    self.factor.insert(f)
                }
            };
            self.numeric_count += 1;
            iters += 1;
            let mut dx = rhs.clone();
            factor.solve_in_place(dx.as_mut());
            // Directional derivative grad . dx = -rhs . dx.
            let mut slope = 0.0;
            let mut step_max = 0.0f64;
            for r in 0..nd {
                slope -= rhs[(r, 0)] * dx[(r, 0)];
                step_max = step_max.max(dx[(r, 0)].abs());
            }
            if !step_max.is_finite() {
                return Err(NewtonError::NonFiniteStep);
            }
            // Backtracking line search (Armijo, c = 1e-4; Nocedal & Wright, Alg. 3.1).
            let mut alpha = 1.0;
            let mut xt = x.clone();
            let mut accepted = false;
            for _ in 0..40 {
                for i in 0..n {
                    if let Some(p) = self.free[i] {
                        let p = 3 * p as usize;
                        xt[i] = axpy(x[i], alpha, [dx[(p, 0)], dx[(p + 1, 0)], dx[(p + 2, 0)]]);
                    }
                }
                let gt = self.objective(m, &xt, &y, h, sp);
                if gt <= g0 + 1e-4 * alpha * slope {
                    g0 = gt;
                    accepted = true;
                    break;
                }
                alpha *= 0.5;
            }
            if !accepted {
                break; // no decrease possible in floating point: at the minimum
            }
            std::mem::swap(&mut x, &mut xt);
            if alpha * step_max < self.opts.tol {
                break;
            }
        }
        for i in 0..n {
            if self.free[i].is_some() {
                let v = sub(x[i], st.x[i]);
                st.v[i] = [
                    v[0] / h * m.damping,
                    v[1] / h * m.damping,
                    v[2] / h * m.damping,
                ];
                st.x[i] = x[i];
            } else {
                st.v[i] = [0.0; 3];
            }
        }
        Ok(iters)
    }
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
