//! The SPH fluid's state: parameters, particles (positions, velocities, densities,
//! pressures), Akinci boundary particles, the per-step neighbour lists, and run statistics;
//! the initial block of fluid at rest; and the symplectic Euler updates every solver ends
//! with (`accelerate`, `advect`). The pressure solvers (`wcsph`, `dfsph`) and the time
//! stepping (`time_step`) build on this module; it depends on none of them.

use super::boundary;
use super::kernel::CubicSpline;
use super::neighbour_grid::{GridError, NeighbourGrid};
use cgnodes_api::types::vec3::{axpy, dot};
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
pub struct Neighbour {
    /// `j`: index of the neighbour (a fluid or a boundary particle).
    pub index: u32,
    /// `W_ij = W(x_i - x_j)`.
    pub w: f64,
    /// `grad W_ij = grad W(x_i - x_j)`.
    pub grad_w: [f64; 3],
}

/// Per-step statistics.
#[derive(Clone, Copy, Debug, Default)]
pub struct StepStats {
    /// Solver iterations this step (density + divergence for DFSPH; 0 for WCSPH).
    pub iterations: usize,
    /// DFSPH solves this step that stopped at `max_iterations` before reaching the tolerance.
    pub capped: usize,
}

/// The fluid: particle state, boundary particles, neighbour lists and run statistics.
#[derive(Clone, Debug)]
pub struct Fluid {
    /// Parameters it was built with.
    pub params: SphParams,
    /// The kernel (support radius `support_factor * r`).
    pub kernel: CubicSpline,
    /// Positions `x_i` (z = 0 in 2-D).
    pub positions: Vec<[f64; 3]>,
    /// Velocities `v_i`.
    pub velocities: Vec<[f64; 3]>,
    /// Densities `rho_i` from the last summation.
    pub densities: Vec<f64>,
    /// Pressures `p_i` from the last step.
    pub pressures: Vec<f64>,
    /// Particle mass `m` (all equal).
    pub mass: f64,
    /// Initial lattice spacing per axis.
    pub spacing: [f64; 3],
    /// Boundary particle positions `x_b` (Akinci 2012).
    pub boundary_positions: Vec<[f64; 3]>,
    /// Boundary particle volumes `V_b` (Akinci 2012 eq. 4).
    pub boundary_volumes: Vec<f64>,
    /// The boundary particles bucketed for neighbour queries (they do not move).
    pub(super) boundary_grid: NeighbourGrid,
    /// Fluid neighbours `j` of each fluid particle `i` (without itself).
    pub fluid_neighbours: Vec<Vec<Neighbour>>,
    /// Boundary neighbours `b` of each fluid particle.
    pub boundary_neighbours: Vec<Vec<Neighbour>>,
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

/// Why `Fluid::block` cannot build a fluid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BlockError {
    /// `SphParams::dim` is neither 2 nor 3.
    #[error("dimension must be 2 or 3, not {0}")]
    Dimension(usize),
    /// The particle radius is not a positive finite number.
    #[error("particle radius must be positive, not {0}")]
    ParticleRadius(f64),
    /// The simulation box has no extent along this axis.
    #[error("the simulation box is empty along axis {0}")]
    EmptySimulationBox(usize),
    /// The fluid block reaches outside the simulation box.
    #[error("the particle box must lie inside the simulation box")]
    ParticleBoxOutside,
    /// The fluid block has no extent along this axis.
    #[error("the particle box is empty along axis {0}")]
    EmptyParticleBox(usize),
    /// The lattice would hold more than 20 million fluid particles.
    #[error("{0} particles is too many (limit 20 million)")]
    TooManyParticles(f64),
    /// Sampling the box walls would take more than 20 million boundary particles.
    #[error(
        "the box walls need {0:.3e} boundary particles (limit 20 million); use a \
         smaller box, larger particles or boundary = walls"
    )]
    TooManyBoundaryParticles(f64),
    /// The boundary particles do not fit a neighbour grid.
    #[error(transparent)]
    Grid(#[from] GridError),
}

/// Particles per axis and lattice spacing per axis of the initial block `[pmin, pmax]`:
/// `counts` per axis (spacing `len / n`), or as many as fit at spacing `2r`. Checks the
/// parameters and boxes first.
fn block_lattice(
    params: &SphParams,
    pmin: [f64; 3],
    pmax: [f64; 3],
    counts: Option<[usize; 3]>,
) -> Result<([usize; 3], [f64; 3]), BlockError> {
    let dim = params.dim;
    if dim != 2 && dim != 3 {
        return Err(BlockError::Dimension(dim));
    }
    let r = params.particle_radius;
    if !(r > 0.0 && r.is_finite()) {
        return Err(BlockError::ParticleRadius(r));
    }
    let mut n = [1usize; 3];
    let mut s = [2.0 * r; 3];
    for a in 0..dim {
        if params.box_max[a] <= params.box_min[a] {
            return Err(BlockError::EmptySimulationBox(a));
        }
        if pmin[a] < params.box_min[a] - 1e-9 || pmax[a] > params.box_max[a] + 1e-9 {
            return Err(BlockError::ParticleBoxOutside);
        }
        let len = pmax[a] - pmin[a];
        if len.is_nan() || len <= 0.0 {
            return Err(BlockError::EmptyParticleBox(a));
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
    Ok((n, s))
}

/// The cell centres of an `n` lattice of spacing `s` from `pmin` (x fastest, then y, z).
fn lattice_points(pmin: [f64; 3], n: [usize; 3], s: [f64; 3], dim: usize) -> Vec<[f64; 3]> {
    let total: f64 = n.iter().map(|&k| k as f64).product();
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
    x
}

/// The sum of `W` over an infinite lattice of spacing `s` around one of its particles
/// (including itself): an interior particle's summed density per unit mass.
fn lattice_kernel_sum(kernel: &CubicSpline, s: [f64; 3], dim: usize) -> f64 {
    let h = kernel.h;
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
    wsum
}

/// Boundary particles of the box walls (Akinci 2012): positions, volumes and their grid;
/// none with `Boundary::Walls`.
type BoundarySampling = (Vec<[f64; 3]>, Vec<f64>, NeighbourGrid);

/// Samples the box walls with `ceil(h / 2r)` layers of boundary particles at spacing `2r`
/// (Akinci 2012), with each particle's lattice volume, when the boundary is `Particles`.
fn wall_particles(
    params: &SphParams,
    kernel: &CubicSpline,
) -> Result<BoundarySampling, BlockError> {
    if params.boundary != Boundary::Particles {
        return Ok((Vec::new(), Vec::new(), NeighbourGrid::default()));
    }
    let (dim, h) = (params.dim, kernel.h);
    let bs = 2.0 * params.particle_radius;
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
        return Err(BlockError::TooManyBoundaryParticles(outer - inner));
    }
    let bx = boundary::box_particles(params.box_min, params.box_max, bs, layers, dim);
    let bgrid = NeighbourGrid::build(&bx, h)?;
    let mut bsp = [bs; 3];
    for (a, sp) in bsp.iter_mut().enumerate().take(dim) {
        let len = params.box_max[a] - params.box_min[a];
        *sp = len / (len / bs).round().max(1.0);
    }
    let bvol = vec![boundary::lattice_volume(bsp, kernel, dim); bx.len()];
    Ok((bx, bvol, bgrid))
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
    ) -> Result<Fluid, BlockError> {
        let (n, s) = block_lattice(&params, pmin, pmax, counts)?;
        let total: f64 = n.iter().map(|&k| k as f64).product();
        if total > 20e6 {
            return Err(BlockError::TooManyParticles(total));
        }
        let dim = params.dim;
        let h = params.support_factor * params.particle_radius;
        let kernel = CubicSpline::new(h, dim);
        let x = lattice_points(pmin, n, s, dim);
        let mass = params.rest_density / lattice_kernel_sum(&kernel, s, dim);
        let (bx, bvol, bgrid) = wall_particles(&params, &kernel)?;
        let np = x.len();
        Ok(Fluid {
            kernel,
            velocities: vec![[0.0; 3]; np],
            densities: vec![params.rest_density; np],
            pressures: vec![0.0; np],
            mass,
            spacing: s,
            positions: x,
            boundary_positions: bx,
            boundary_volumes: bvol,
            boundary_grid: bgrid,
            fluid_neighbours: Vec::new(),
            boundary_neighbours: Vec::new(),
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
        self.positions.len()
    }

    /// Whether there are no fluid particles.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// The up axis (y in 2-D, z in 3-D), along which gravity acts.
    pub fn up(&self) -> usize {
        self.params.dim - 1
    }

    /// The velocity update of symplectic Euler: `v += dt a` for every particle.
    pub fn accelerate(&mut self, acc: &[[f64; 3]], dt: f64) {
        self.velocities
            .par_iter_mut()
            .zip(acc.par_iter())
            .for_each(|(v, a)| {
                *v = axpy(*v, dt, *a);
            });
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
        self.positions
            .par_iter_mut()
            .zip(self.velocities.par_iter_mut())
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
}
