//! The fluid state shared by the SPH solvers: particles, boundary particles, neighbour
//! lists, SPH density summation, the non-pressure accelerations, the time step and the
//! frame loop with blow-up detection. The pressure solvers are in `wcsph.rs` and `dfsph.rs`.

use super::boundary;
use super::grid::Grid;
use super::kernel::CubicSpline;
use rayon::prelude::*;

/// Which pressure solver advances the fluid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Solver {
    /// Weakly compressible SPH with the course's equation of state (Becker & Teschner 2007).
    Wcsph,
    /// Divergence-free SPH (Bender & Koschier 2015/2017): a constant-density and a
    /// divergence-free solver, both Jacobi iterations on the velocities.
    Dfsph,
}

/// How the simulation box holds the fluid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Boundary {
    /// Akinci et al. 2012 boundary particles (plus the wall clamp as a safety net).
    Particles,
    /// Only the wall clamp: positions projected into the box, normal velocity reflected
    /// with the restitution.
    Walls,
}

/// Parameters of a simulation (Framework3D's `geom_sph_fluid` names where it has them).
#[derive(Clone, Debug, PartialEq)]
pub struct SphParams {
    /// 2 or 3.
    pub dim: usize,
    /// Pressure solver.
    pub solver: Solver,
    /// Boundary handling.
    pub boundary: Boundary,
    /// Simulation box corners.
    pub box_min: [f64; 3],
    /// Simulation box corners.
    pub box_max: [f64; 3],
    /// Particle radius `r`; the initial spacing is `2r` unless particle counts are given.
    pub particle_radius: f64,
    /// Support radius as a multiple of `r` (4 in the course).
    pub support_factor: f64,
    /// Rest density `rho0` (kg/m^d).
    pub rest_density: f64,
    /// WCSPH stiffness `k` in `p = k((rho/rho0)^gamma - 1)`.
    pub stiffness: f64,
    /// WCSPH exponent `gamma`.
    pub exponent: f64,
    /// Kinematic viscosity `nu` of the course's viscosity Laplacian.
    pub viscosity: f64,
    /// Gravity along the up axis (y in 2-D, z in 3-D).
    pub gravity: f64,
    /// Time step (the largest one when adaptive).
    pub dt: f64,
    /// CFL number for the adaptive step (`dt <= cfl * 2r / v_max`); 0 keeps `dt` fixed.
    pub cfl: f64,
    /// Restitution of the wall clamp (0 = inelastic).
    pub restitution: f64,
    /// Iteration limit of the DFSPH solvers.
    pub max_iterations: usize,
    /// Target average density error of the DFSPH density solver (fraction, e.g. 1e-3).
    pub max_density_error: f64,
    /// Whether DFSPH runs its divergence-free solver.
    pub divergence: bool,
}

impl Default for SphParams {
    fn default() -> Self {
        SphParams {
            dim: 3,
            solver: Solver::Wcsph,
            boundary: Boundary::Particles,
            box_min: [0.0; 3],
            box_max: [1.0; 3],
            particle_radius: 0.025,
            support_factor: 4.0,
            rest_density: 1000.0,
            stiffness: 500.0,
            exponent: 7.0,
            viscosity: 0.03,
            gravity: -9.8,
            dt: 0.01,
            cfl: 0.4,
            restitution: 0.0,
            max_iterations: 1000,
            max_density_error: 1e-3,
            divergence: true,
        }
    }
}

/// A neighbour `j` of particle `i` with the kernel and its gradient at `x_i - x_j`,
/// computed once per step and reused by every solver iteration.
#[derive(Clone, Copy, Debug)]
pub struct Nb {
    /// Index of the neighbour (a fluid or a boundary particle).
    pub j: u32,
    /// `W(x_i - x_j)`.
    pub w: f64,
    /// `grad W(x_i - x_j)`.
    pub g: [f64; 3],
}

/// Per-step statistics.
#[derive(Clone, Copy, Debug, Default)]
pub struct StepStats {
    /// Solver iterations this step (density + divergence for DFSPH; 0 for WCSPH).
    pub iterations: usize,
    /// DFSPH solves this step that stopped at `max_iterations` before reaching the tolerance.
    pub capped: usize,
}

/// The fluid: particle state, boundary particles, neighbour lists and scratch arrays.
#[derive(Clone, Debug)]
pub struct Fluid {
    /// Parameters it was built with.
    pub params: SphParams,
    /// The kernel (support radius `support_factor * r`).
    pub kernel: CubicSpline,
    /// Positions (z = 0 in 2-D).
    pub x: Vec<[f64; 3]>,
    /// Velocities.
    pub v: Vec<[f64; 3]>,
    /// Densities from the last summation.
    pub rho: Vec<f64>,
    /// Pressures from the last step.
    pub p: Vec<f64>,
    /// Particle mass (all equal).
    pub mass: f64,
    /// Initial lattice spacing per axis.
    pub spacing: [f64; 3],
    /// Boundary particle positions.
    pub bx: Vec<[f64; 3]>,
    /// Boundary particle volumes (Akinci 2012).
    pub bvol: Vec<f64>,
    bgrid: Grid,
    /// Fluid neighbours of each fluid particle (without itself).
    pub nbf: Vec<Vec<Nb>>,
    /// Boundary neighbours of each fluid particle.
    pub nbb: Vec<Vec<Nb>>,
    /// Simulated time.
    pub time: f64,
    /// Steps taken.
    pub steps: usize,
    /// Iterations of the last step.
    pub last: StepStats,
    /// Solver iterations over all steps.
    pub total_iterations: usize,
    /// DFSPH solves over all steps stopped by `max_iterations` (unconverged).
    pub capped_solves: usize,
}

pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub(crate) fn axpy(s: f64, a: [f64; 3], y: &mut [f64; 3]) {
    y[0] += s * a[0];
    y[1] += s * a[1];
    y[2] += s * a[2];
}

impl Fluid {
    /// A block of fluid at rest filling `[pmin, pmax]`: `counts` particles per axis (cell
    /// centres of a regular lattice), or spacing `2r` when `counts` is `None`. The particle
    /// mass makes an interior lattice particle sit exactly at the rest density:
    /// `m = rho0 / sum_lattice W`.
    pub fn block(
        params: SphParams,
        pmin: [f64; 3],
        pmax: [f64; 3],
        counts: Option<[usize; 3]>,
    ) -> Result<Fluid, String> {
        let dim = params.dim;
        if dim != 2 && dim != 3 {
            return Err(format!("dimension must be 2 or 3, not {dim}"));
        }
        let r = params.particle_radius;
        if !(r > 0.0 && r.is_finite()) {
            return Err(format!("particle radius must be positive, not {r}"));
        }
        let mut n = [1usize; 3];
        let mut s = [2.0 * r; 3];
        for a in 0..dim {
            if params.box_max[a] <= params.box_min[a] {
                return Err(format!("the simulation box is empty along axis {a}"));
            }
            if pmin[a] < params.box_min[a] - 1e-9 || pmax[a] > params.box_max[a] + 1e-9 {
                return Err("the particle box must lie inside the simulation box".into());
            }
            let len = pmax[a] - pmin[a];
            if len.is_nan() || len <= 0.0 {
                return Err(format!("the particle box is empty along axis {a}"));
            }
            match counts {
                Some(c) => {
                    n[a] = c[a].max(1);
                    s[a] = len / n[a] as f64;
                }
                None => {
                    n[a] = ((len / s[a]) + 1e-9).floor().max(1.0) as usize;
                }
            }
        }
        let total: f64 = n.iter().map(|&k| k as f64).product();
        if total > 20e6 {
            return Err(format!("{total} particles is too many (limit 20 million)"));
        }
        let h = params.support_factor * r;
        let kernel = CubicSpline::new(h, dim);
        let mut x = Vec::with_capacity(total as usize);
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let idx = [i, j, k];
                    let mut p = [0.0; 3];
                    for a in 0..dim {
                        p[a] = pmin[a] + (idx[a] as f64 + 0.5) * s[a];
                    }
                    x.push(p);
                }
            }
        }
        // Lattice sum of W over an infinite lattice of this spacing (incl. the particle).
        let mut wsum = 0.0;
        let m = [
            (h / s[0]).ceil() as i64,
            (h / s[1]).ceil() as i64,
            if dim == 3 {
                (h / s[2]).ceil() as i64
            } else {
                0
            },
        ];
        for k in -m[2]..=m[2] {
            for j in -m[1]..=m[1] {
                for i in -m[0]..=m[0] {
                    let d = [i as f64 * s[0], j as f64 * s[1], k as f64 * s[2]];
                    wsum += kernel.w(dot(d, d).sqrt());
                }
            }
        }
        let mass = params.rest_density / wsum;
        let (bx, bvol, bgrid) = if params.boundary == Boundary::Particles {
            let bs = 2.0 * r;
            let layers = (h / bs).ceil() as usize;
            let (mut outer, mut inner) = (1.0f64, 1.0f64);
            for a in 0..dim {
                let n = ((params.box_max[a] - params.box_min[a]) / bs)
                    .round()
                    .max(1.0);
                outer *= n + 2.0 * layers as f64;
                inner *= n;
            }
            if outer - inner > 20e6 {
                return Err(format!(
                    "the box walls need {:.3e} boundary particles (limit 20 million); use a \
                     smaller box, larger particles or boundary = walls",
                    outer - inner
                ));
            }
            let bx = boundary::box_particles(params.box_min, params.box_max, bs, layers, dim);
            let bgrid = Grid::build(&bx, h)?;
            let mut bsp = [bs; 3];
            for (a, sp) in bsp.iter_mut().enumerate().take(dim) {
                let len = params.box_max[a] - params.box_min[a];
                *sp = len / (len / bs).round().max(1.0);
            }
            let bvol = vec![boundary::lattice_volume(bsp, &kernel, dim); bx.len()];
            (bx, bvol, bgrid)
        } else {
            (Vec::new(), Vec::new(), Grid::default())
        };
        let np = x.len();
        Ok(Fluid {
            kernel,
            v: vec![[0.0; 3]; np],
            rho: vec![params.rest_density; np],
            p: vec![0.0; np],
            mass,
            spacing: s,
            x,
            bx,
            bvol,
            bgrid,
            nbf: Vec::new(),
            nbb: Vec::new(),
            time: 0.0,
            steps: 0,
            last: StepStats::default(),
            total_iterations: 0,
            capped_solves: 0,
            params,
        })
    }

    /// Number of fluid particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there are no fluid particles.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// The up axis (y in 2-D, z in 3-D), along which gravity acts.
    pub fn up(&self) -> usize {
        self.params.dim - 1
    }

    /// Rebuilds the neighbour lists (uniform grid, cell = support radius) with the kernel
    /// values and gradients at the current positions.
    pub fn find_neighbours(&mut self) -> Result<(), String> {
        let h = self.kernel.h;
        let grid = Grid::build(&self.x, h)?;
        let kern = self.kernel;
        let x = &self.x;
        let bx = &self.bx;
        let bgrid = &self.bgrid;
        let lists: Vec<(Vec<Nb>, Vec<Nb>)> = (0..x.len())
            .into_par_iter()
            .map(|i| {
                let xi = x[i];
                let mut f = Vec::with_capacity(48);
                grid.for_each_candidate(&xi, |j| {
                    if j == i {
                        return;
                    }
                    let d = sub(xi, x[j]);
                    let r2 = dot(d, d);
                    if r2 < h * h {
                        f.push(Nb {
                            j: j as u32,
                            w: kern.w(r2.sqrt()),
                            g: kern.grad(d),
                        });
                    }
                });
                let mut b = Vec::new();
                bgrid.for_each_candidate(&xi, |j| {
                    let d = sub(xi, bx[j]);
                    let r2 = dot(d, d);
                    if r2 < h * h {
                        b.push(Nb {
                            j: j as u32,
                            w: kern.w(r2.sqrt()),
                            g: kern.grad(d),
                        });
                    }
                });
                (f, b)
            })
            .collect();
        let (f, b): (Vec<_>, Vec<_>) = lists.into_iter().unzip();
        self.nbf = f;
        self.nbb = b;
        Ok(())
    }

    /// Density by summation including the particle itself, plus the boundary particles'
    /// `rho0 V_b W_ib` (Akinci 2012 eq. 6): `rho_i = m (W(0) + sum_j W_ij) + rho0 sum_b V_b W_ib`.
    pub fn compute_densities(&mut self) {
        let m = self.mass;
        let w0 = self.kernel.w_zero();
        let rho0 = self.params.rest_density;
        let bvol = &self.bvol;
        self.rho = self
            .nbf
            .par_iter()
            .zip(self.nbb.par_iter())
            .map(|(f, b)| {
                let sf: f64 = f.iter().map(|n| n.w).sum();
                let sb: f64 = b.iter().map(|n| bvol[n.j as usize] * n.w).sum();
                m * (w0 + sf) + rho0 * sb
            })
            .collect();
    }

    /// Gravity plus the course's viscosity, the SPH Laplacian of Koschier et al. 2019
    /// eq. (32): `a_i = 2(d+2) nu sum_j (m/rho_ij) (v_ij . x_ij) / (|x_ij|^2 + 0.01 h^2) grad W_ij`,
    /// with `rho_ij = (rho_i + rho_j)/2` so that the pair forces are equal and opposite.
    pub fn non_pressure_accelerations(&self) -> Vec<[f64; 3]> {
        let d = self.params.dim as f64;
        let nu = self.params.viscosity;
        let m = self.mass;
        let h2 = self.kernel.h * self.kernel.h;
        let mut g = [0.0; 3];
        g[self.up()] = self.params.gravity;
        let (x, v, rho) = (&self.x, &self.v, &self.rho);
        self.nbf
            .par_iter()
            .enumerate()
            .map(|(i, nb)| {
                let mut a = g;
                if nu > 0.0 {
                    let c = 2.0 * (d + 2.0) * nu * m;
                    for n in nb {
                        let j = n.j as usize;
                        let xij = sub(x[i], x[j]);
                        let vij = sub(v[i], v[j]);
                        let s = c * dot(vij, xij)
                            / (0.5 * (rho[i] + rho[j]) * (dot(xij, xij) + 0.01 * h2));
                        axpy(s, n.g, &mut a);
                    }
                }
                a
            })
            .collect()
    }

    /// Largest speed.
    pub fn max_speed(&self) -> f64 {
        self.v
            .par_iter()
            .map(|v| dot(*v, *v))
            .reduce(|| 0.0, f64::max)
            .sqrt()
    }

    /// The next step size: `dt`, or with `cfl > 0` the CFL bound `cfl * 2r / v_max`, the
    /// explicit viscosity bound, and for WCSPH also `cfl * h / c` with the EOS sound speed
    /// `c = sqrt(k gamma / rho0)`.
    pub fn step_size(&self) -> f64 {
        let p = &self.params;
        if p.cfl <= 0.0 {
            return p.dt;
        }
        let mut dt = p.dt;
        let vmax = self.max_speed() + (p.gravity.abs() * p.dt);
        if vmax > 0.0 {
            dt = dt.min(p.cfl * 2.0 * p.particle_radius / vmax);
        }
        if p.viscosity > 0.0 {
            // Explicit viscosity: dt <= 0.125 l^2 / nu with the smoothing length l = h/2
            // (Monaghan 1992).
            let l = 0.5 * self.kernel.h;
            dt = dt.min(0.125 * l * l / p.viscosity);
        }
        if p.solver == Solver::Wcsph && p.stiffness > 0.0 {
            let c = (p.stiffness * p.exponent / p.rest_density).sqrt();
            dt = dt.min(p.cfl * self.kernel.h / c);
        }
        dt.max(p.dt * 1e-4)
    }

    /// Moves the particles `x += dt v` and clamps them into the box, reflecting the normal
    /// velocity with the restitution.
    pub fn advect(&mut self, dt: f64) {
        let dim = self.params.dim;
        let (lo, hi, e) = (
            self.params.box_min,
            self.params.box_max,
            self.params.restitution,
        );
        self.x
            .par_iter_mut()
            .zip(self.v.par_iter_mut())
            .for_each(|(x, v)| {
                for a in 0..dim {
                    x[a] += dt * v[a];
                    if x[a] < lo[a] {
                        x[a] = lo[a];
                        if v[a] < 0.0 {
                            v[a] *= -e;
                        }
                    } else if x[a] > hi[a] {
                        x[a] = hi[a];
                        if v[a] > 0.0 {
                            v[a] *= -e;
                        }
                    }
                }
            });
    }

    /// One time step of size `dt` with the configured solver.
    pub fn step(&mut self, dt: f64) -> Result<(), String> {
        self.last = match self.params.solver {
            Solver::Wcsph => super::wcsph::step(self, dt)?,
            Solver::Dfsph => super::dfsph::step(self, dt)?,
        };
        self.time += dt;
        self.steps += 1;
        self.total_iterations += self.last.iterations;
        self.capped_solves += self.last.capped;
        self.check()
    }

    /// Advances by `duration` in steps of `step_size()`; `Err` names the step that blew up.
    pub fn advance(&mut self, duration: f64) -> Result<usize, String> {
        let mut left = duration;
        let mut n = 0;
        while left > 1e-12 * duration.max(1e-12) {
            let mut dt = self.step_size().min(left);
            // Avoid a sliver of a last step.
            if left - dt < 0.2 * dt {
                dt = if left <= dt { left } else { 0.5 * left };
            }
            self.step(dt).map_err(|e| {
                format!(
                    "step {} (t = {:.4} s, dt = {dt:.2e}): {e}",
                    self.steps, self.time
                )
            })?;
            left -= dt;
            n += 1;
        }
        Ok(n)
    }

    /// Blow-up detection: non-finite state, a speed far beyond free fall over the box, or
    /// a fluid compressed to five times its rest density (particles piling up; the course's
    /// stiffness 500 legitimately reaches 1.6x at the bottom of a 1.25 m column at rest).
    fn check(&self) -> Result<(), String> {
        let p = &self.params;
        let mut diag = 0.0;
        for a in 0..p.dim {
            diag += (p.box_max[a] - p.box_min[a]).powi(2);
        }
        let vlim = 50.0 * (2.0 * p.gravity.abs().max(1.0) * diag.sqrt()).sqrt();
        let bad = self
            .x
            .par_iter()
            .zip(self.v.par_iter())
            .position_any(|(x, v)| {
                !(x.iter().all(|c| c.is_finite()) && v.iter().all(|c| c.is_finite()))
                    || dot(*v, *v) > vlim * vlim
            });
        if let Some(i) = bad {
            return Err(format!(
                "particle {i} has position {:?} and velocity {:?} (speed limit {vlim:.1} m/s); \
                 lower dt, enable the adaptive step, or raise the stiffness",
                self.x[i], self.v[i]
            ));
        }
        let rmax = self.rho.iter().cloned().fold(0.0, f64::max);
        if rmax.is_nan() || rmax >= 5.0 * p.rest_density {
            return Err(format!(
                "the density reached {rmax:.1} (rest density {}); the fluid is collapsing: \
                 raise the stiffness or lower dt",
                p.rest_density
            ));
        }
        Ok(())
    }

    /// Recomputes neighbours and densities at the current positions (for output).
    pub fn refresh(&mut self) -> Result<(), String> {
        self.find_neighbours()?;
        self.compute_densities();
        Ok(())
    }

    /// Largest and average compression `max(rho/rho0 - 1, 0)` (free-surface particles
    /// lack neighbours and read low densities, which is not an error).
    pub fn density_error(&self) -> (f64, f64) {
        let rho0 = self.params.rest_density;
        let e: Vec<f64> = self.rho.iter().map(|r| (r / rho0 - 1.0).max(0.0)).collect();
        let max = e.iter().cloned().fold(0.0, f64::max);
        let avg = if e.is_empty() {
            0.0
        } else {
            e.iter().sum::<f64>() / e.len() as f64
        };
        (max, avg)
    }

    /// Kinetic energy `1/2 m sum |v|^2`.
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.mass * self.v.iter().map(|v| dot(*v, *v)).sum::<f64>()
    }

    /// Total momentum `m sum v`.
    pub fn momentum(&self) -> [f64; 3] {
        let mut s = [0.0; 3];
        for v in &self.v {
            axpy(self.mass, *v, &mut s);
        }
        s
    }

    /// Front position along +x, measured from the box's left wall: the 5th-largest particle
    /// x (robust against a few splashed particles, as in the SPlisHSPlasH measurement of
    /// `PEERS.md`) plus half a spacing (the particle's extent).
    pub fn front(&self) -> f64 {
        if self.x.is_empty() {
            return 0.0;
        }
        let mut xs: Vec<f64> = self.x.iter().map(|p| p[0]).collect();
        let k = 4.min(xs.len() - 1);
        let idx = xs.len() - 1 - k;
        let (_, kth, _) = xs.select_nth_unstable_by(idx, |a, b| a.total_cmp(b));
        *kth + 0.5 * self.spacing[0] - self.params.box_min[0]
    }

    /// Height of the fluid above the floor (largest up coordinate plus half a spacing).
    pub fn height(&self) -> f64 {
        let up = self.up();
        self.x.iter().map(|p| p[up]).fold(f64::MIN, f64::max) + 0.5 * self.spacing[up]
            - self.params.box_min[up]
    }
}
