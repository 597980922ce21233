//! Backward Euler by L-BFGS with the projective-dynamics matrix as its initial Hessian (Liu,
//! Bouaziz & Kavan 2017, "Quasi-Newton Methods for Real-Time Simulation of Hyperelastic
//! Materials", ACM TOG 36(3), Alg. 1).
//!
//! The objective is the implicit integrator's `g(x) = 1/(2h^2) (x-y)^T M (x-y) + E(x)`
//! (`incremental_potential`); the search direction comes from the L-BFGS two-loop recursion
//! (Nocedal & Wright 2006, Alg. 7.4) whose initial inverse Hessian is a solve with
//! `M/h^2 + L`, the global matrix of Liu et al. 2013 (eq. 16), factored once per model and
//! time step (`projective::global_factor`). An iteration is one gradient, one pair of
//! triangular solves for the three coordinates, a few dot products and the line search's
//! energy evaluations, whatever the stiffness: where Newton's CG iterations grow with the
//! stiffness per mass, the quasi-Newton iteration's cost does not. Armijo backtracking keeps
//! `g` decreasing; it stops, like Newton, when no vertex moves more than `tol` in an iteration.

use super::implicit::{end_step, incremental_potential, NewtonError};
use super::projective::global_factor;
use super::springs::{
    add_collider_forces, spring_forces, sub, Incidence, Model, SetupError, Sphere, State,
};
use cgnodes_linalg::SpdFactor;
use faer::MatMut;
use std::collections::VecDeque;

/// Quasi-Newton options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuasiNewtonOptions {
    /// Most iterations per step.
    pub max_iters: usize,
    /// Stop when the largest vertex move of an iteration is below this (length units).
    pub tol: f64,
    /// Correction pairs kept (Liu et al. 2017 use 5).
    pub history: usize,
}

impl Default for QuasiNewtonOptions {
    fn default() -> Self {
        QuasiNewtonOptions {
            max_iters: 100,
            tol: 1e-7,
            history: 5,
        }
    }
}

/// One L-BFGS correction pair: the step `s`, the gradient change `y` and `1 / sᵀy`.
struct Pair {
    s: Vec<f64>,
    y: Vec<f64>,
    rho: f64,
}

/// The quasi-Newton integrator's state: the factored initial Hessian and the buffers.
pub struct QuasiNewton {
    free: Vec<Option<u32>>,
    n_free: usize,
    factor: SpdFactor,
    h: f64,
    inc: Incidence,
    f: Vec<[f64; 3]>,
    pairs: VecDeque<Pair>,
    /// Pairs dropped from `pairs`, kept for their memory (a step's buffers are a few
    /// megabytes at 128x128: fresh ones every step would page-fault them in again).
    spare: Vec<Pair>,
    /// Gradient, next gradient and search direction (`3 n_free` each), kept between steps.
    buffers: [Vec<f64>; 3],
    /// Options.
    pub opts: QuasiNewtonOptions,
    /// Iterations over all steps.
    pub iterations: usize,
}

/// `aᵀb`.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `a += t b`.
fn axpy(a: &mut [f64], t: f64, b: &[f64]) {
    a.iter_mut().zip(b).for_each(|(x, y)| *x += t * y);
}

impl QuasiNewton {
    /// Factors `M/h^2 + L` over the free vertices of `m`.
    pub fn new(m: &Model, h: f64, opts: QuasiNewtonOptions) -> Result<QuasiNewton, SetupError> {
        let (free, n_free, factor) = global_factor(m, h)?;
        let n = m.num_vertices();
        Ok(QuasiNewton {
            free,
            n_free,
            factor,
            h,
            inc: Incidence::new(&m.springs, n),
            f: vec![[0.0; 3]; n],
            pairs: VecDeque::new(),
            spare: Vec::new(),
            buffers: [Vec::new(), Vec::new(), Vec::new()],
            opts,
            iterations: 0,
        })
    }

    /// The time step the matrix was factored for.
    pub fn h(&self) -> f64 {
        self.h
    }

    /// `∇g(x)` on the free vertices into `grad` (`3 n_free`, one coordinate after the
    /// other); returns its largest magnitude.
    fn gradient(
        &mut self,
        m: &Model,
        x: &[[f64; 3]],
        y: &[[f64; 3]],
        sp: Option<&Sphere>,
        grad: &mut [f64],
    ) -> f64 {
        spring_forces(&self.inc, x, &mut self.f);
        add_collider_forces(sp, x, &m.fixed, &mut self.f);
        let (nf, ih2) = (self.n_free, 1.0 / (self.h * self.h));
        let mut gmax = 0.0f64;
        for (i, slot) in self.free.iter().enumerate() {
            if let Some(p) = *slot {
                let d = sub(x[i], y[i]);
                for c in 0..3 {
                    let g = m.mass[i] * ih2 * d[c] - self.f[i][c];
                    grad[c * nf + p as usize] = g;
                    gmax = gmax.max(g.abs());
                }
            }
        }
        gmax
    }

    /// `d = -H⁻¹ grad` by the two-loop recursion over the stored pairs, `H0⁻¹` a solve with
    /// the global matrix.
    fn direction(&self, grad: &[f64], d: &mut [f64], alphas: &mut Vec<f64>) {
        d.copy_from_slice(grad);
        alphas.clear();
        for p in self.pairs.iter().rev() {
            let a = p.rho * dot(&p.s, d);
            axpy(d, -a, &p.y);
            alphas.push(a);
        }
        // x on one core, y and z on the other: the triangular solves are memory-bound and
        // both read the same factor
        let (dx, dyz) = d.split_at_mut(self.n_free);
        rayon::join(
            || {
                self.factor
                    .solve_in_place(MatMut::from_column_major_slice_mut(dx, self.n_free, 1))
            },
            || {
                self.factor
                    .solve_in_place(MatMut::from_column_major_slice_mut(dyz, self.n_free, 2))
            },
        );
        for (p, &a) in self.pairs.iter().zip(alphas.iter().rev()) {
            let b = p.rho * dot(&p.y, d);
            axpy(d, a - b, &p.s);
        }
        d.iter_mut().for_each(|v| *v = -*v);
    }

    /// Advances `st` by one backward Euler step; returns the iterations. Fails when the
    /// state is not finite.
    pub fn step(
        &mut self,
        m: &Model,
        st: &mut State,
        sp: Option<&Sphere>,
    ) -> Result<usize, NewtonError> {
        let (nf, h) = (self.n_free, self.h);
        let y = m.inertial_positions(st, h);
        let mut x = y.clone();
        let mut xt = x.clone();
        // the pairs describe the previous step's objective: start afresh
        self.spare.extend(self.pairs.drain(..));
        let [mut grad, mut grad_new, mut d] = std::mem::take(&mut self.buffers);
        for v in [&mut grad, &mut grad_new, &mut d] {
            v.resize(3 * nf, 0.0);
        }
        let mut alphas = Vec::new();
        let mut gmax = self.gradient(m, &x, &y, sp, &mut grad);
        let mut g0 = incremental_potential(m, &x, &y, h, sp);
        let mut iters = 0;
        while iters < self.opts.max_iters {
            if !gmax.is_finite() {
                return Err(NewtonError::NonFiniteGradient);
            }
            if gmax == 0.0 {
                break;
            }
            self.direction(&grad, &mut d, &mut alphas);
            let mut slope = dot(&grad, &d);
            if slope.is_nan() || slope >= 0.0 {
                // not a descent direction (curvature information gone stale): H0 alone
                self.spare.extend(self.pairs.drain(..));
                self.direction(&grad, &mut d, &mut alphas);
                slope = dot(&grad, &d);
            }
            let step_max = d.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            if !step_max.is_finite() {
                return Err(NewtonError::NonFiniteStep);
            }
            iters += 1;
            // Backtracking line search (Armijo, c = 1e-4; Nocedal & Wright, Alg. 3.1).
            let mut alpha = 1.0;
            let mut accepted = false;
            for _ in 0..40 {
                for (i, slot) in self.free.iter().enumerate() {
                    if let Some(p) = *slot {
                        let p = p as usize;
                        for c in 0..3 {
                            xt[i][c] = x[i][c] + alpha * d[c * nf + p];
                        }
                    }
                }
                let gt = incremental_potential(m, &xt, &y, h, sp);
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
            let gmax_new = self.gradient(m, &xt, &y, sp, &mut grad_new);
            // the correction pair: s = alpha d, y = grad_new - grad
            if self.pairs.len() >= self.opts.history.max(1) {
                self.spare.extend(self.pairs.pop_front());
            }
            let mut pair = self.spare.pop().unwrap_or_else(|| Pair {
                s: vec![0.0; 3 * nf],
                y: vec![0.0; 3 * nf],
                rho: 0.0,
            });
            pair.s.resize(3 * nf, 0.0);
            pair.y.resize(3 * nf, 0.0);
            for k in 0..3 * nf {
                pair.s[k] = alpha * d[k];
                pair.y[k] = grad_new[k] - grad[k];
            }
            let sy = dot(&pair.s, &pair.y);
            if sy > 0.0 && sy.is_finite() && self.opts.history > 0 {
                pair.rho = 1.0 / sy;
                self.pairs.push_back(pair);
            } else {
                self.spare.push(pair);
            }
            std::mem::swap(&mut x, &mut xt);
            std::mem::swap(&mut grad, &mut grad_new);
            gmax = gmax_new;
            if alpha * step_max < self.opts.tol {
                break;
            }
        }
        self.iterations += iters;
        self.buffers = [grad, grad_new, d];
        end_step(m, st, &x, h);
        Ok(iters)
    }
}

#[cfg(test)]
mod tests {
    use super::super::implicit::tests::max_diff;
    use super::super::implicit::{Implicit, LinearSolver, NewtonOptions};
    use super::*;
    use crate::mass_spring::{energy, springs_from_mesh, SpringKinds};
    use cgnodes_geometry::grid::grid_mesh;

    /// An `n x n` sheet of 1 cm spacing with the stiffness per mass of the issue-59 scene
    /// (stretch and shear springs k = 1000, 1/128² kg per vertex), gravity -y. `taut`: the
    /// boundary fixed at 5 % stretch, so every spring stays in tension and the step's
    /// minimizer is unique; otherwise two corners fixed, hanging.
    fn sheet(n: usize, taut: bool) -> (Model, Vec<[f64; 3]>) {
        let s = 0.01 * (n - 1) as f64;
        let mesh = grid_mesh(n - 1, n - 1, [s, s], "xz", [s / 2.0, 0.0, s / 2.0], false).unwrap();
        let kinds = SpringKinds {
            shear: true,
            bending: false,
            bending_scale: 1.0,
        };
        let nv = mesh.num_vertices();
        let fixed: Vec<bool> = (0..nv)
            .map(|v| {
                let (i, j) = (v % n, v / n);
                if taut {
                    i == 0 || j == 0 || i == n - 1 || j == n - 1
                } else {
                    v == 0 || v == n - 1
                }
            })
            .collect();
        let model = Model {
            springs: springs_from_mesh(&mesh, 1000.0, kinds),
            mass: vec![1.0 / (128.0 * 128.0); nv],
            fixed,
            gravity: [0.0, -9.8, 0.0],
            damping: 1.0,
        };
        let stretch = if taut { 1.05 } else { 1.0 };
        let x0 = mesh
            .positions
            .iter()
            .map(|p| [p[0] * stretch, p[1], p[2] * stretch])
            .collect();
        (model, x0)
    }

    fn newton(model: &Model) -> Implicit {
        let opts = NewtonOptions {
            solver: LinearSolver::Cholesky,
            tol: 1e-12,
            max_iters: 50,
            ..Default::default()
        };
        Implicit::new(model, opts)
    }

    /// Ten steps by both integrators on the taut stiff sheet, with the largest difference of
    /// positions over the steps.
    fn against_newton(n: usize, tol: f64) -> (f64, usize, State) {
        let (model, x0) = sheet(n, true);
        let h = 1.0 / 60.0;
        let mut a = State {
            x: x0.clone(),
            v: vec![[0.0; 3]; x0.len()],
        };
        let mut b = a.clone();
        let mut exact = newton(&model);
        let opts = QuasiNewtonOptions {
            tol,
            max_iters: 1000,
            ..Default::default()
        };
        let mut qn = QuasiNewton::new(&model, h, opts).unwrap();
        let (mut worst, mut most): (f64, usize) = (0.0, 0);
        for _ in 0..10 {
            exact.step(&model, &mut a, h, None).unwrap();
            most = most.max(qn.step(&model, &mut b, None).unwrap());
            worst = worst.max(max_diff(&a.x, &b.x));
            assert!(b
                .x
                .iter()
                .zip(&x0)
                .zip(&model.fixed)
                .all(|((p, q), f)| !f || p == q));
        }
        (worst, most, a)
    }

    /// Both integrators minimize the same objective: with a tight tolerance the quasi-Newton
    /// steps land on Newton's exact (Cholesky) steps, step after step, on a sheet that sags.
    #[test]
    fn quasi_newton_reaches_the_newton_step_on_a_stiff_sheet() {
        let (worst, most, a) = against_newton(16, 1e-11);
        assert!(worst < 1e-8, "{worst:e} m from Newton's steps");
        assert!(most < 1000, "{most} iterations");
        // the middle sagged (the comparison is not between two sheets at rest)
        assert!(a.x[8 * 16 + 8][1] < -5e-5, "{:?}", a.x[8 * 16 + 8]);
    }

    /// At the benchmark's tolerance (1e-5 m, a thousandth of the spacing) the steps stay
    /// within 15 tolerances of Newton's (8.6e-5 m measured: a move below the tolerance is
    /// not a distance to the minimizer), in far fewer iterations.
    #[test]
    fn a_looser_tolerance_stays_near_the_newton_step() {
        let (worst, most, _) = against_newton(16, 1e-5);
        assert!(worst < 1.5e-4, "{worst:e} m");
        let (_, most_tight, _) = against_newton(16, 1e-11);
        assert!(most < most_tight, "{most} against {most_tight} iterations");
    }

    /// Large steps on the hanging stiff sheet stay bounded: no NaN, and the energy after ten
    /// steps of 0.1 s is not above its start (backward Euler dissipates).
    #[test]
    fn large_steps_stay_bounded() {
        let (model, x0) = sheet(12, false);
        let h = 0.1;
        let mut st = State {
            x: x0.clone(),
            v: vec![[0.0; 3]; x0.len()],
        };
        let mut qn = QuasiNewton::new(&model, h, QuasiNewtonOptions::default()).unwrap();
        let e0 = energy(&model, &st, &x0, None).total();
        for _ in 0..10 {
            qn.step(&model, &mut st, None).unwrap();
        }
        let e = energy(&model, &st, &x0, None).total();
        assert!(e.is_finite() && e <= e0, "{e} > {e0}");
    }
}
