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
//! is `S^T H S dx = -S^T grad g`, Baraff & Witkin 1998 §5.3 in its reduced form).
//!
//! The Newton system is solved either by sparse Cholesky (`newton_direct.rs`: symbolic
//! analysis once per model, one numeric factorization and one solve per Newton step) or,
//! above `PCG_MIN_UNKNOWNS` unknowns, matrix-free by block-Jacobi preconditioned conjugate
//! gradients to a relative residual `cg_tol` (`newton_pcg.rs`): at 128x128 a Newton
//! iteration then costs about 20x less than a numeric factorization and solve
//! (docs/mass_spring.md). The projection of each spring's Hessian onto PSD keeps `H`
//! positive definite with either solver; nothing is refactored to fix definiteness.

use super::newton_direct::HessianCholesky;
use super::newton_pcg::{HessianPcg, Preconditioner};
use super::springs::{
    add_collider_forces, axpy, collider_energy, dot, spring_energy, spring_forces, sub, Incidence,
    Model, Sphere, State,
};
use faer::Mat;
use std::time::Instant;

/// Backward Euler's objective `g(x) = 1/(2h^2) (x-y)^T M (x-y) + E(x)` (spring and collider
/// energy), without the constant part of fixed vertices: its minimizer is the step's end.
pub(super) fn incremental_potential(
    m: &Model,
    x: &[[f64; 3]],
    y: &[[f64; 3]],
    h: f64,
    sp: Option<&Sphere>,
) -> f64 {
    let mut inertia = 0.0;
    for i in 0..x.len() {
        if !m.fixed[i] {
            let d = sub(x[i], y[i]);
            inertia += 0.5 * m.mass[i] * dot(d, d);
        }
    }
    inertia / (h * h) + spring_energy(&m.springs, x).0 + collider_energy(sp, x, &m.fixed)
}

/// Moves `st` to the minimizer `x` of a backward Euler step of length `h`:
/// `v = damping (x - x_n) / h` for free vertices, zero for fixed ones.
pub(super) fn end_step(m: &Model, st: &mut State, x: &[[f64; 3]], h: f64) {
    for i in 0..x.len() {
        if m.fixed[i] {
            st.v[i] = [0.0; 3];
        } else {
            let v = sub(x[i], st.x[i]);
            st.v[i] = [
                v[0] / h * m.damping,
                v[1] / h * m.damping,
                v[2] / h * m.damping,
            ];
            st.x[i] = x[i];
        }
    }
}

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

/// How each Newton system is solved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LinearSolver {
    /// `Pcg` from `PCG_MIN_UNKNOWNS` free unknowns on, `Cholesky` below.
    #[default]
    Auto,
    /// Sparse Cholesky: exact Newton steps.
    Cholesky,
    /// Block-Jacobi preconditioned conjugate gradients to `cg_tol` (falls back to
    /// `Cholesky` for a Newton step whose CG fails).
    Pcg,
}

/// From this many free unknowns (3 per free vertex) on, `LinearSolver::Auto` uses PCG.
/// Below it a Newton step is cheap with either solver and the Cholesky's steps are exact
/// (small course grids keep their results of before PCG).
pub const PCG_MIN_UNKNOWNS: usize = 1000;

/// Newton options.
#[derive(Clone, Copy, Debug)]
pub struct NewtonOptions {
    /// Most Newton iterations per step.
    pub max_iters: usize,
    /// Stop when the largest vertex move of a Newton step is below this (length units).
    pub tol: f64,
    /// How the Newton systems are solved.
    pub solver: LinearSolver,
    /// PCG: stop when `|H dx + grad| <= cg_tol |grad|` (the inexact Newton forcing term).
    pub cg_tol: f64,
    /// PCG: most CG iterations per Newton step before falling back to Cholesky.
    pub cg_max_iters: usize,
    /// PCG: the preconditioner.
    pub preconditioner: Preconditioner,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        NewtonOptions {
            max_iters: 20,
            tol: 1e-7,
            solver: LinearSolver::Auto,
            cg_tol: 1e-3,
            cg_max_iters: 1000,
            preconditioner: Preconditioner::Auto,
        }
    }
}

/// Where the Newton solver's time went, summed over all steps (seconds), with counts.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NewtonProfile {
    /// Newton iterations (one linear solve each).
    pub iterations: usize,
    /// Forces and gradient.
    pub gradient: f64,
    /// Hessian: spring blocks (PCG) or sparse values (Cholesky).
    pub assemble: f64,
    /// The first factorization: symbolic analysis (AMD) and numeric.
    pub first_factor: f64,
    /// Later numeric factorizations.
    pub factor: f64,
    /// Triangular solves, or the CG solves.
    pub solve: f64,
    /// Backtracking line search (objective evaluations).
    pub line_search: f64,
    /// CG iterations.
    pub cg_iterations: usize,
    /// Newton steps whose CG failed and were solved by Cholesky instead.
    pub cg_fallbacks: usize,
}

/// The implicit integrator's solver state: the sparse Cholesky and the PCG workspaces, each
/// built at its first use, and the force buffers.
pub struct Implicit {
    free: Vec<bool>,
    n_free: usize,
    direct: Option<HessianCholesky>,
    pcg: Option<HessianPcg>,
    inc: Incidence,
    f: Vec<[f64; 3]>,
    /// Newton options.
    pub opts: NewtonOptions,
    /// How many symbolic factorizations were computed (0 before the first Newton step that
    /// uses the Cholesky, then 1 for the life of the solver).
    pub symbolic_count: usize,
    /// How many numeric factorizations were computed.
    pub numeric_count: usize,
    /// Time per phase, summed over all steps.
    pub profile: NewtonProfile,
}

impl Implicit {
    /// The solver for `m`; the Hessian's pattern or blocks are built at the first step.
    pub fn new(m: &Model, opts: NewtonOptions) -> Implicit {
        let n = m.num_vertices();
        let (_, n_free) = m.free_indices();
        Implicit {
            free: m.fixed.iter().map(|f| !f).collect(),
            n_free,
            direct: None,
            pcg: None,
            inc: Incidence::new(&m.springs, n),
            f: vec![[0.0; 3]; n],
            opts,
            symbolic_count: 0,
            numeric_count: 0,
            profile: NewtonProfile::default(),
        }
    }

    /// Whether Newton systems are solved by PCG (after resolving `LinearSolver::Auto`).
    pub fn uses_pcg(&self) -> bool {
        match self.opts.solver {
            LinearSolver::Auto => 3 * self.n_free >= PCG_MIN_UNKNOWNS,
            LinearSolver::Cholesky => false,
            LinearSolver::Pcg => true,
        }
    }

    /// The Newton direction `dx` solving `H(x) dx = rhs` (`rhs = -grad g`, three entries per
    /// vertex, zero at fixed vertices): by PCG, or by Cholesky when PCG is not used or fails.
    #[allow(clippy::too_many_arguments)]
    fn direction(
        &mut self,
        m: &Model,
        x: &[[f64; 3]],
        ih2: f64,
        sp: Option<&Sphere>,
        rhs: &Mat<f64>,
        dx: &mut Mat<f64>,
        first: bool,
    ) -> Result<(), NewtonError> {
        if self.uses_pcg() {
            let t = Instant::now();
            let pre = self.opts.preconditioner;
            let pcg = self.pcg.get_or_insert_with(|| {
                let mut p = HessianPcg::new(m);
                p.preconditioner = pre;
                p
            });
            pcg.assemble(m, x, ih2, sp);
            self.profile.assemble += t.elapsed().as_secs_f64();
            let t = Instant::now();
            let (tol, max) = (self.opts.cg_tol, self.opts.cg_max_iters);
            let res = pcg.solve(rhs.as_ref(), dx.as_mut(), first, tol, max);
            self.profile.solve += t.elapsed().as_secs_f64();
            match res {
                Ok(out) => {
                    self.profile.cg_iterations += out.iterations;
                    return Ok(());
                }
                Err(_) => self.profile.cg_fallbacks += 1,
            }
        }
        let t = Instant::now();
        let direct = self.direct.get_or_insert_with(|| HessianCholesky::new(m));
        direct.assemble(m, x, ih2, sp);
        self.profile.assemble += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let first_factor = direct.symbolic_count == 0;
        direct
            .factor()
            .map_err(|e| NewtonError::NotPositiveDefinite(e.to_string()))?;
        let dt = t.elapsed().as_secs_f64();
        if first_factor {
            self.profile.first_factor += dt;
        } else {
            self.profile.factor += dt;
        }
        (self.symbolic_count, self.numeric_count) = (direct.symbolic_count, direct.numeric_count);
        let t = Instant::now();
        dx.copy_from(rhs);
        direct
            .solve(dx.as_mut())
            .map_err(|e| NewtonError::NotPositiveDefinite(e.to_string()))?;
        self.profile.solve += t.elapsed().as_secs_f64();
        Ok(())
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
        let mut iters = 0;
        let mut g0 = incremental_potential(m, &x, &y, h, sp);
        let mut rhs = Mat::<f64>::zeros(3 * n, 1);
        let mut dx = Mat::<f64>::zeros(3 * n, 1);
        let mut xt = x.clone();
        for it in 0..self.opts.max_iters {
            let t = Instant::now();
            // Gradient of g over free vertices: M/h^2 (x - y) - f(x).
            self.f.resize(n, [0.0; 3]);
            spring_forces(&self.inc, &x, &mut self.f);
            add_collider_forces(sp, &x, &m.fixed, &mut self.f);
            let mut gmax = 0.0f64;
            for i in 0..n {
                if self.free[i] {
                    let grad = axpy(
                        [-self.f[i][0], -self.f[i][1], -self.f[i][2]],
                        m.mass[i] * ih2,
                        sub(x[i], y[i]),
                    );
                    for a in 0..3 {
                        rhs[(3 * i + a, 0)] = -grad[a];
                        gmax = gmax.max(grad[a].abs());
                    }
                }
            }
            self.profile.gradient += t.elapsed().as_secs_f64();
            if !gmax.is_finite() {
                return Err(NewtonError::NonFiniteGradient);
            }
            if gmax == 0.0 {
                break;
            }
            self.direction(m, &x, ih2, sp, &rhs, &mut dx, it == 0)?;
            self.profile.iterations += 1;
            iters += 1;
            let t = Instant::now();
            // Directional derivative grad . dx = -rhs . dx.
            let mut slope = 0.0;
            let mut step_max = 0.0f64;
            for r in 0..3 * n {
                slope -= rhs[(r, 0)] * dx[(r, 0)];
                step_max = step_max.max(dx[(r, 0)].abs());
            }
            if !step_max.is_finite() {
                return Err(NewtonError::NonFiniteStep);
            }
            // Backtracking line search (Armijo, c = 1e-4; Nocedal & Wright, Alg. 3.1).
            let mut alpha = 1.0;
            let mut accepted = false;
            for _ in 0..40 {
                for i in 0..n {
                    if self.free[i] {
                        let p = 3 * i;
                        xt[i] = axpy(x[i], alpha, [dx[(p, 0)], dx[(p + 1, 0)], dx[(p + 2, 0)]]);
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
            self.profile.line_search += t.elapsed().as_secs_f64();
            if !accepted {
                break; // no decrease possible in floating point: at the minimum
            }
            std::mem::swap(&mut x, &mut xt);
            if alpha * step_max < self.opts.tol {
                break;
            }
        }
        end_step(m, st, &x, h);
        Ok(iters)
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::super::newton_direct::HessianCholesky;
    use super::super::newton_pcg::HessianPcg;
    use super::*;
    use crate::mass_spring::{springs_from_mesh, SpringKinds};
    use cgnodes_geometry::grid::grid_mesh;

    /// An `n x n` cloth (spacing 0.1, structural, shear and bending springs, k = 1000,
    /// 0.1 kg per vertex) in the xz plane, two corners of the first row fixed, gravity -y:
    /// the setup of `cargo bench --bench cloth`.
    fn cloth(n: usize) -> (Model, Vec<[f64; 3]>) {
        let s = 0.1 * (n - 1) as f64;
        let mesh = grid_mesh(n - 1, n - 1, [s, s], "xz", [s / 2.0, 0.0, s / 2.0], false).unwrap();
        let kinds = SpringKinds {
            shear: true,
            bending: true,
            bending_scale: 1.0,
        };
        let nv = mesh.num_vertices();
        let mut fixed = vec![false; nv];
        (fixed[0], fixed[n - 1]) = (true, true);
        let model = Model {
            springs: springs_from_mesh(&mesh, 1000.0, kinds),
            mass: vec![0.1; nv],
            fixed,
            gravity: [0.0, -9.81, 0.0],
            damping: 1.0,
        };
        (model, mesh.positions)
    }

    /// Runs `steps` backward Euler steps with `solver`; returns the positions after each
    /// step, the Newton iterations of each step and the solver.
    fn run(
        model: &Model,
        x0: &[[f64; 3]],
        sp: Option<&Sphere>,
        opts: NewtonOptions,
        steps: usize,
    ) -> (Vec<Vec<[f64; 3]>>, Vec<usize>, Implicit) {
        let mut st = State {
            x: x0.to_vec(),
            v: vec![[0.0; 3]; x0.len()],
        };
        let mut solver = Implicit::new(model, opts);
        let (mut xs, mut its) = (Vec::new(), Vec::new());
        for _ in 0..steps {
            its.push(solver.step(model, &mut st, 1.0 / 60.0, sp).unwrap());
            xs.push(st.x.clone());
        }
        (xs, its, solver)
    }

    /// The largest coordinate difference between two position sets.
    pub(in crate::mass_spring) fn max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
        (a.iter().zip(b))
            .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
            .fold(0.0, f64::max)
    }

    fn with(solver: LinearSolver) -> NewtonOptions {
        NewtonOptions {
            solver,
            ..Default::default()
        }
    }

    #[test]
    fn pcg_operator_is_the_assembled_hessian() {
        // Stretched, compressed and out-of-plane springs, two fixed vertices and vertices
        // inside the sphere's contact shell.
        let (model, x0) = cloth(7);
        let x: Vec<[f64; 3]> = (x0.iter().enumerate())
            .map(|(i, p)| {
                let w = (i * 7919 % 17) as f64 / 17.0 - 0.5;
                [
                    p[0] * (1.0 + 0.2 * w),
                    p[1] + 0.03 * w,
                    p[2] * (1.0 - 0.15 * w),
                ]
            })
            .collect();
        let sphere = Sphere {
            center: [0.3, -0.25, 0.3],
            radius: 0.3,
            k: 1e4,
            scale: 1.1,
        };
        let ih2 = 3600.0;
        let mut direct = HessianCholesky::new(&model);
        direct.assemble(&model, &x, ih2, Some(&sphere));
        direct.factor().unwrap();
        let mut pcg = HessianPcg::new(&model);
        pcg.assemble(&model, &x, ih2, Some(&sphere));
        let n = x.len();
        for seed in 1..4usize {
            // b = H^-1 r by the Cholesky, then H b by the operator must give r back.
            let r: Vec<f64> = (0..3 * n)
                .map(|i| match model.fixed[i / 3] {
                    true => 0.0,
                    false => ((i * 2654435761 * seed) % 1000) as f64 / 500.0 - 1.0,
                })
                .collect();
            let mut b = Mat::<f64>::from_fn(3 * n, 1, |i, _| r[i]);
            direct.solve(b.as_mut()).unwrap();
            let b: Vec<f64> = (0..3 * n).map(|i| b[(i, 0)]).collect();
            let mut hb = vec![0.0; 3 * n];
            pcg.apply(&b, &mut hb);
            let err = (hb.iter().zip(&r))
                .map(|(p, q)| (p - q).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-9, "seed {seed}: |H H^-1 r - r| = {err:e}");
        }
    }

    #[test]
    fn pcg_trajectory_matches_cholesky() {
        // Hanging cloth, 40 steps at h = 1/60, PCG at the default tolerance against the
        // exact Newton steps of the Cholesky.
        let (model, x0) = cloth(12);
        let (xs_c, it_c, chol) = run(&model, &x0, None, with(LinearSolver::Cholesky), 40);
        let (xs_p, it_p, pcg) = run(&model, &x0, None, with(LinearSolver::Pcg), 40);
        for (k, (a, b)) in xs_c.iter().zip(&xs_p).enumerate() {
            let d = max_diff(a, b);
            assert!(d < 1e-6, "step {k}: PCG and Cholesky differ by {d:e}");
        }
        // the cloth moved: the comparison is not between two rest states
        assert!(max_diff(&xs_c[39], &x0) > 0.1);
        let total_c: usize = it_c.iter().sum();
        let total_p: usize = it_p.iter().sum();
        assert!(
            total_p <= total_c + 4,
            "Newton iterations {total_p} vs {total_c}"
        );
        assert_eq!(pcg.numeric_count, 0, "PCG factored");
        assert_eq!(pcg.profile.cg_fallbacks, 0);
        assert!(pcg.profile.cg_iterations > 0);
        assert_eq!(chol.symbolic_count, 1);
        assert_eq!(chol.numeric_count, total_c);
    }

    #[test]
    fn pcg_trajectory_matches_cholesky_with_contact() {
        // Cloth falling onto the penalty sphere: contact blocks enter the Hessian.
        let (mut model, x0) = cloth(10);
        model.fixed.iter_mut().for_each(|f| *f = false);
        let sphere = Sphere {
            center: [0.45, -0.35, 0.45],
            radius: 0.25,
            k: 1e4,
            scale: 1.1,
        };
        let sp = Some(&sphere);
        let (xs_c, _, _) = run(&model, &x0, sp, with(LinearSolver::Cholesky), 30);
        let (xs_p, _, _) = run(&model, &x0, sp, with(LinearSolver::Pcg), 30);
        let touching = xs_c[29]
            .iter()
            .filter(|p| super::super::springs::norm(sub(**p, sphere.center)) < 1.1 * 0.25)
            .count();
        assert!(touching > 0, "the cloth never reached the sphere");
        for (k, (a, b)) in xs_c.iter().zip(&xs_p).enumerate() {
            let d = max_diff(a, b);
            assert!(d < 1e-6, "step {k}: PCG and Cholesky differ by {d:e}");
        }
    }

    #[test]
    fn axis_laplacians_follow_cholesky_on_stiff_cloth_in_fewer_cg_iterations() {
        // Centimetre spacing and 1 kg over the sheet: k/m per vertex is 1.6e5 times the
        // bench scene's, where block Jacobi's CG iterations grow.
        let n = 24;
        let (mut model, _) = cloth(n);
        let s = 0.01 * (n - 1) as f64;
        let mesh = grid_mesh(n - 1, n - 1, [s, s], "xz", [s / 2.0, 0.0, s / 2.0], false).unwrap();
        let nv = mesh.num_vertices();
        model.mass = vec![1.0 / nv as f64; nv];
        model.springs = springs_from_mesh(&mesh, 1000.0, SpringKinds::default());
        let x0 = mesh.positions;
        let pcg = |p| NewtonOptions {
            preconditioner: p,
            ..with(LinearSolver::Pcg)
        };
        let (xs_c, _, _) = run(&model, &x0, None, with(LinearSolver::Cholesky), 4);
        let (xs_j, _, jac) = run(&model, &x0, None, pcg(Preconditioner::BlockJacobi), 4);
        let (xs_a, _, axes) = run(&model, &x0, None, pcg(Preconditioner::AxisLaplacians), 4);
        for k in 0..4 {
            for xs in [&xs_j, &xs_a] {
                let d = max_diff(&xs_c[k], &xs[k]);
                assert!(d < 1e-6, "step {k}: PCG and Cholesky differ by {d:e}");
            }
        }
        assert!(max_diff(&xs_c[3], &x0) > 1e-3, "the cloth did not move");
        let (cj, ca) = (jac.profile.cg_iterations, axes.profile.cg_iterations);
        assert!(
            2 * ca < cj,
            "CG iterations: axis Laplacians {ca}, block Jacobi {cj}"
        );
        assert_eq!(axes.profile.cg_fallbacks, 0);
    }

    #[test]
    fn failed_cg_falls_back_to_the_exact_step() {
        // One CG iteration never reaches the tolerance: every Newton step falls back to the
        // Cholesky and the trajectory is the Cholesky's, bit for bit.
        let (model, x0) = cloth(8);
        let (xs_c, it_c, _) = run(&model, &x0, None, with(LinearSolver::Cholesky), 5);
        let opts = NewtonOptions {
            cg_max_iters: 1,
            ..with(LinearSolver::Pcg)
        };
        let (xs_p, it_p, pcg) = run(&model, &x0, None, opts, 5);
        assert_eq!(xs_c, xs_p);
        assert_eq!(it_c, it_p);
        assert_eq!(pcg.profile.cg_fallbacks, it_p.iter().sum::<usize>());
    }

    #[test]
    fn auto_uses_pcg_from_the_threshold_on() {
        let small = cloth(8).0; // 62 free vertices
        let large = cloth(19).0; // 359 free vertices
        const { assert!(3 * 62 < PCG_MIN_UNKNOWNS && 3 * 359 >= PCG_MIN_UNKNOWNS) };
        let opts = NewtonOptions::default();
        assert!(!Implicit::new(&small, opts).uses_pcg());
        assert!(Implicit::new(&large, opts).uses_pcg());
        assert!(Implicit::new(&small, with(LinearSolver::Pcg)).uses_pcg());
        assert!(!Implicit::new(&large, with(LinearSolver::Cholesky)).uses_pcg());
    }
}
