//! The mass-spring model as plain data: springs built from a mesh, per-vertex masses,
//! fixed vertices, gravity and a sphere collider, with the energy, forces and Hessian
//! blocks every integrator shares.
//!
//! Spring energy (Hooke, as in the course's assignment 8): `E_s = 1/2 k (|x_j - x_i| - L)^2`.
//! Sphere penalty (course): `E_c = 1/2 k_p (s r - |x - c|)^2` when `|x - c| < s r`, `s` = 1.1.

use cgnodes_api::prelude::*;
use rayon::prelude::*;
use std::collections::HashSet;

/// Smallest chunk of springs (or vertices) a rayon task gets: below a few thousand items the
/// loops run serially, where thread hand-off would cost more than it saves.
const PAR_MIN: usize = 8192;

/// Springs as index pairs with rest lengths and stiffnesses.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Springs {
    /// End vertices of each spring.
    pub ends: Vec<[u32; 2]>,
    /// Rest length of each spring.
    pub rest: Vec<f64>,
    /// Stiffness of each spring.
    pub k: Vec<f64>,
}

impl Springs {
    /// Number of springs.
    pub fn len(&self) -> usize {
        self.ends.len()
    }
    /// Whether there are no springs.
    pub fn is_empty(&self) -> bool {
        self.ends.is_empty()
    }
    /// Adds a spring between `a` and `b` at rest at the distance in `x`.
    pub fn push(&mut self, a: u32, b: u32, x: &[[f64; 3]], k: f64) {
        self.ends.push([a, b]);
        self.rest.push(norm(sub(x[b as usize], x[a as usize])));
        self.k.push(k);
    }
}

/// Which springs to build from a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpringKinds {
    /// Across the diagonals of polygons with 4 or more corners (triangle meshes already
    /// have their diagonals as edges).
    pub shear: bool,
    /// Skip-one springs along straight lines of the mesh (Provot 1995's flexion springs):
    /// `a - v - b` where the edges `va` and `vb` are nearly opposite at rest.
    pub bending: bool,
    /// Stiffness factor of bending springs relative to `k`.
    pub bending_scale: f64,
}

impl Default for SpringKinds {
    fn default() -> Self {
        SpringKinds {
            shear: true,
            bending: false,
            bending_scale: 1.0,
        }
    }
}

/// Builds springs from a mesh's edges (structural), polygon diagonals (shear) and
/// straight skip-one pairs (bending), without duplicates.
pub fn springs_from_mesh(mesh: &Mesh, k: f64, kinds: SpringKinds) -> Springs {
    let x = &mesh.positions;
    let mut seen: HashSet<(u32, u32)> = HashSet::new();
    let mut s = Springs::default();
    let mut add = |s: &mut Springs, a: u32, b: u32, k: f64| {
        if a != b && seen.insert((a.min(b), a.max(b))) {
            s.push(a.min(b), a.max(b), x, k);
        }
    };
    let topo = mesh.topology();
    for e in &topo.edges {
        add(&mut s, e[0], e[1], k);
    }
    if kinds.shear {
        for f in mesh.faces() {
            let n = f.len();
            if n < 4 {
                continue;
            }
            for i in 0..n {
                for j in i + 2..n {
                    if i == 0 && j == n - 1 {
                        continue;
                    }
                    add(&mut s, f[i], f[j], k);
                }
            }
        }
    }
    if kinds.bending {
        let kb = k * kinds.bending_scale;
        for v in 0..mesh.num_vertices() {
            let nb = topo.neighbors(v);
            for (ia, &a) in nb.iter().enumerate() {
                for &b in &nb[ia + 1..] {
                    let da = sub(x[a as usize], x[v]);
                    let db = sub(x[b as usize], x[v]);
                    let c = dot(da, db) / (norm(da) * norm(db)).max(1e-300);
                    // cos < -0.95: the two edges continue each other (angle > ~162 degrees).
                    if c < -0.95 {
                        add(&mut s, a, b, kb);
                    }
                }
            }
        }
    }
    // Sort by end vertices: force passes then walk memory in order (vertex-local access),
    // which at 100k springs is several times faster than the construction order.
    let mut order: Vec<usize> = (0..s.len()).collect();
    order.sort_by_key(|&i| s.ends[i]);
    Springs {
        ends: order.iter().map(|&i| s.ends[i]).collect(),
        rest: order.iter().map(|&i| s.rest[i]).collect(),
        k: order.iter().map(|&i| s.k[i]).collect(),
    }
}

/// A sphere collider at one instant (course: penalty force outside `scale * radius`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: [f64; 3],
    /// Radius of the visible sphere.
    pub radius: f64,
    /// Penalty stiffness `k_p`.
    pub k: f64,
    /// Contact starts at `scale * radius` (the course uses 1.1).
    pub scale: f64,
}

impl Sphere {
    /// The contact radius `scale * radius`.
    pub fn contact_radius(&self) -> f64 {
        self.scale * self.radius
    }
}

/// Everything that defines the dynamics except the state.
#[derive(Clone, Debug, Default)]
pub struct Model {
    /// The springs.
    pub springs: Springs,
    /// Mass of each vertex (> 0).
    pub mass: Vec<f64>,
    /// Vertices that never move.
    pub fixed: Vec<bool>,
    /// Gravitational acceleration vector.
    pub gravity: [f64; 3],
    /// Velocity factor applied after every step (1 = none; the course uses 0.995).
    pub damping: f64,
}

impl Model {
    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.mass.len()
    }

    /// The index of each vertex among the free (not fixed) ones, `None` when fixed, and the
    /// number of free vertices: the unknowns of the implicit solvers' reduced systems.
    pub fn free_indices(&self) -> (Vec<Option<u32>>, usize) {
        let n = self.num_vertices();
        let mut free = vec![None; n];
        let mut n_free = 0usize;
        for i in 0..n {
            if !self.fixed[i] {
                free[i] = Some(n_free as u32);
                n_free += 1;
            }
        }
        (free, n_free)
    }

    /// The inertial positions `y = x + h v + h^2 g` of backward Euler's objective (fixed
    /// vertices stay where they are).
    pub fn inertial_positions(&self, st: &State, h: f64) -> Vec<[f64; 3]> {
        (0..self.num_vertices())
            .map(|i| {
                if self.fixed[i] {
                    st.x[i]
                } else {
                    axpy(axpy(st.x[i], h, st.v[i]), h * h, self.gravity)
                }
            })
            .collect()
    }

    /// Checks sizes and values; `Err` says what is wrong.
    pub fn check(&self) -> Result<(), ModelError> {
        let n = self.mass.len();
        if self.fixed.len() != n {
            return Err(ModelError::FixedFlags {
                flags: self.fixed.len(),
                vertices: n,
            });
        }
        if let Some(i) = self.mass.iter().position(|m| !(m.is_finite() && *m > 0.0)) {
            return Err(ModelError::Mass {
                vertex: i,
                mass: self.mass[i],
            });
        }
        for (s, e) in self.springs.ends.iter().enumerate() {
            if e[0] as usize >= n || e[1] as usize >= n {
                return Err(ModelError::SpringEnd {
                    spring: s,
                    vertices: n,
                });
            }
            if !(self.springs.rest[s] > 0.0 && self.springs.rest[s].is_finite()) {
                return Err(ModelError::RestLength {
                    spring: s,
                    ends: *e,
                    rest: self.springs.rest[s],
                });
            }
            if !(self.springs.k[s] >= 0.0 && self.springs.k[s].is_finite()) {
                return Err(ModelError::Stiffness {
                    spring: s,
                    k: self.springs.k[s],
                });
            }
        }
        if !(self.damping.is_finite() && self.damping > 0.0 && self.damping <= 1.0) {
            return Err(ModelError::Damping(self.damping));
        }
        if self.gravity.iter().any(|g| !g.is_finite()) {
            return Err(ModelError::Gravity);
        }
        Ok(())
    }
}

/// What `Model::check` found wrong with a model.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// The fixed flags and the masses differ in count.
    #[error("{flags} fixed flags for {vertices} vertices")]
    FixedFlags {
        /// Number of fixed flags.
        flags: usize,
        /// Number of vertices (masses).
        vertices: usize,
    },
    /// A vertex mass is not positive and finite.
    #[error("vertex {vertex} has mass {mass} (must be > 0)")]
    Mass {
        /// The vertex.
        vertex: usize,
        /// Its mass.
        mass: f64,
    },
    /// A spring refers to a vertex index past the end.
    #[error("spring {spring} refers to a vertex beyond {vertices}")]
    SpringEnd {
        /// The spring.
        spring: usize,
        /// Number of vertices.
        vertices: usize,
    },
    /// A spring's rest length is not positive and finite.
    #[error("spring {spring} ({}, {}) has rest length {rest} (coincident vertices?)", ends[0], ends[1])]
    RestLength {
        /// The spring.
        spring: usize,
        /// Its two vertices.
        ends: [u32; 2],
        /// Its rest length.
        rest: f64,
    },
    /// A spring's stiffness is negative or not finite.
    #[error("spring {spring} has stiffness {k}")]
    Stiffness {
        /// The spring.
        spring: usize,
        /// Its stiffness.
        k: f64,
    },
    /// The damping factor is outside (0, 1].
    #[error("damping {0} is not in (0, 1]")]
    Damping(f64),
    /// Gravity has a non-finite component.
    #[error("gravity is not finite")]
    Gravity,
}

/// Positions and velocities.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct State {
    /// Positions.
    pub x: Vec<[f64; 3]>,
    /// Velocities.
    pub v: Vec<[f64; 3]>,
}

/// Energies of a state; potential energy of gravity is measured from `x_ref`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energy {
    /// `1/2 sum m |v|^2`.
    pub kinetic: f64,
    /// Springs + gravity + collider penalty.
    pub potential: f64,
    /// Largest `|l - L| / L` over the springs.
    pub max_strain: f64,
}

impl Energy {
    /// Kinetic plus potential.
    pub fn total(&self) -> f64 {
        self.kinetic + self.potential
    }
}

/// Spring energy and the largest strain.
pub fn spring_energy(s: &Springs, x: &[[f64; 3]]) -> (f64, f64) {
    (0..s.len())
        .into_par_iter()
        .with_min_len(PAR_MIN)
        .map(|i| {
            let [a, b] = s.ends[i];
            let l = norm(sub(x[b as usize], x[a as usize]));
            let d = l - s.rest[i];
            (0.5 * s.k[i] * d * d, (d / s.rest[i]).abs())
        })
        .reduce(|| (0.0, 0.0), |p, q| (p.0 + q.0, p.1.max(q.1)))
}

/// Penalty energy of the sphere collider.
pub fn collider_energy(sphere: Option<&Sphere>, x: &[[f64; 3]], fixed: &[bool]) -> f64 {
    let Some(sp) = sphere else { return 0.0 };
    let r = sp.contact_radius();
    x.iter()
        .zip(fixed)
        .filter(|(_, f)| !**f)
        .map(|(p, _)| {
            let d = norm(sub(*p, sp.center));
            if d < r {
                0.5 * sp.k * (r - d) * (r - d)
            } else {
                0.0
            }
        })
        .sum()
}

/// Kinetic, potential (springs, gravity from `x_ref`, collider) and maximum strain.
pub fn energy(m: &Model, st: &State, x_ref: &[[f64; 3]], sphere: Option<&Sphere>) -> Energy {
    let (es, strain) = spring_energy(&m.springs, &st.x);
    let mut kin = 0.0;
    let mut grav = 0.0;
    for i in 0..m.num_vertices() {
        kin += 0.5 * m.mass[i] * dot(st.v[i], st.v[i]);
        grav -= m.mass[i] * dot(m.gravity, sub(st.x[i], x_ref[i]));
    }
    Energy {
        kinetic: kin,
        potential: es + grav + collider_energy(sphere, &st.x, &m.fixed),
        max_strain: strain,
    }
}

/// Springs seen from each vertex (CSR): for vertex `v`, the other end, rest length and
/// stiffness of each incident spring. Forces are then gathered per vertex in parallel without
/// atomics or a per-spring buffer; each spring is evaluated from both ends, which costs less
/// than the memory traffic it saves.
#[derive(Clone, Debug, Default)]
pub struct Incidence {
    /// Start of each vertex's list.
    pub start: Vec<usize>,
    /// Other end of each incident spring.
    pub other: Vec<u32>,
    /// Rest length of each incident spring.
    pub rest: Vec<f64>,
    /// Stiffness of each incident spring.
    pub k: Vec<f64>,
}

impl Incidence {
    /// Builds the incidence of `s` over `n` vertices.
    pub fn new(s: &Springs, n: usize) -> Incidence {
        let mut start = vec![0usize; n + 1];
        for e in &s.ends {
            start[e[0] as usize + 1] += 1;
            start[e[1] as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let m = start[n];
        let (mut other, mut rest, mut k) = (vec![0u32; m], vec![0.0; m], vec![0.0; m]);
        for (i, e) in s.ends.iter().enumerate() {
            for (v, u) in [(e[0], e[1]), (e[1], e[0])] {
                let j = fill[v as usize];
                other[j] = u;
                rest[j] = s.rest[i];
                k[j] = s.k[i];
                fill[v as usize] += 1;
            }
        }
        Incidence {
            start,
            other,
            rest,
            k,
        }
    }
}

/// Spring forces per vertex, `f = -dE_s/dx`, written into `f` (overwritten):
/// vertex `v` is pulled towards `u` by `k (l - L) / l (x_u - x_v)` for each spring `(v, u)`.
pub fn spring_forces(inc: &Incidence, x: &[[f64; 3]], f: &mut [[f64; 3]]) {
    f.par_iter_mut()
        .with_min_len(PAR_MIN / 2)
        .enumerate()
        .for_each(|(v, out)| {
            let xv = x[v];
            let mut acc = [0.0; 3];
            for j in inc.start[v]..inc.start[v + 1] {
                let d = sub(x[inc.other[j] as usize], xv);
                let l = norm(d);
                if l > 0.0 {
                    acc = axpy(acc, inc.k[j] * (1.0 - inc.rest[j] / l), d);
                }
            }
            *out = acc;
        });
}

/// Adds the sphere's penalty force `k_p (s r - d) n` to `f` (free vertices only).
pub fn add_collider_forces(
    sphere: Option<&Sphere>,
    x: &[[f64; 3]],
    fixed: &[bool],
    f: &mut [[f64; 3]],
) {
    let Some(sp) = sphere else { return };
    let r = sp.contact_radius();
    for i in 0..x.len() {
        if fixed[i] {
            continue;
        }
        let d = sub(x[i], sp.center);
        let l = norm(d);
        if l < r && l > 0.0 {
            f[i] = axpy(f[i], sp.k * (r - l) / l, d);
        }
    }
}

/// The 3x3 Hessian block `K` of one spring's energy with respect to `x_1 - x_0`,
/// projected to be positive semi-definite: `K = k n n^T + k max(0, 1 - L/l) (I - n n^T)`.
/// The exact block has eigenvalues `k` (along `n`) and `k (1 - L/l)` (twice), negative when
/// the spring is compressed; clamping them at zero is the per-spring PSD projection
/// (Teran et al. 2005 style, applied per element).
pub fn spring_hessian_psd(d: [f64; 3], rest: f64, k: f64) -> [[f64; 3]; 3] {
    let l = norm(d);
    if l <= 0.0 {
        return [[0.0; 3]; 3];
    }
    let n = scale(d, 1.0 / l);
    let t = k * (1.0 - rest / l).max(0.0);
    let mut h = [[0.0; 3]; 3];
    for (a, row) in h.iter_mut().enumerate() {
        for (b, e) in row.iter_mut().enumerate() {
            let id = if a == b { 1.0 } else { 0.0 };
            *e = k * n[a] * n[b] + t * (id - n[a] * n[b]);
        }
    }
    h
}

pub use cgnodes_api::types::vec3::{axpy, dot, norm, scale, sub};

/// Why a simulator over a model could not be built (here, below both the `Simulator` and
/// the integrators that report it).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SetupError {
    /// The model is inconsistent (`Model::check`).
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The initial state or the time step is invalid.
    #[error("{0}")]
    Invalid(String),
    /// The projective integrator's global matrix could not be factored.
    #[error("{0}")]
    NotPositiveDefinite(String),
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_spring(x1: [f64; 3]) -> (Springs, Vec<[f64; 3]>) {
        let rest = vec![[0.0; 3], [1.0, 0.0, 0.0]];
        let mut s = Springs::default();
        s.push(0, 1, &rest, 7.0);
        (s, vec![[0.0; 3], x1])
    }

    #[test]
    fn forces_are_minus_energy_gradient() {
        let (s, x) = one_spring([1.3, 0.4, -0.2]);
        let inc = Incidence::new(&s, 2);
        let mut f = vec![[0.0; 3]; 2];
        spring_forces(&inc, &x, &mut f);
        let eps = 1e-6;
        for v in 0..2 {
            for c in 0..3 {
                let mut xp = x.clone();
                let mut xm = x.clone();
                xp[v][c] += eps;
                xm[v][c] -= eps;
                let g = (spring_energy(&s, &xp).0 - spring_energy(&s, &xm).0) / (2.0 * eps);
                assert!(
                    (f[v][c] + g).abs() < 1e-6,
                    "v{v} c{c}: {} vs {}",
                    f[v][c],
                    -g
                );
            }
        }
    }

    #[test]
    fn hessian_is_exact_when_stretched_and_psd_when_compressed() {
        for (x1, stretched) in [([1.3, 0.4, -0.2], true), ([0.5, 0.2, 0.1], false)] {
            let (s, x) = one_spring(x1);
            let d = sub(x[1], x[0]);
            let k = spring_hessian_psd(d, s.rest[0], s.k[0]);
            // Finite-difference Hessian of the energy w.r.t. x1 (= w.r.t. d).
            let inc = Incidence::new(&s, 2);
            let eps = 1e-6;
            let mut exact = [[0.0; 3]; 3];
            for c in 0..3 {
                let mut fp = vec![[0.0; 3]; 2];
                let mut fm = vec![[0.0; 3]; 2];
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[1][c] += eps;
                xm[1][c] -= eps;
                spring_forces(&inc, &xp, &mut fp);
                spring_forces(&inc, &xm, &mut fm);
                for r in 0..3 {
                    exact[r][c] = -(fp[1][r] - fm[1][r]) / (2.0 * eps);
                }
            }
            let km = nalgebra::Matrix3::from_fn(|r, c| k[r][c]);
            let em = nalgebra::Matrix3::from_fn(|r, c| exact[r][c]);
            let ev = km.symmetric_eigen().eigenvalues;
            assert!(ev.iter().all(|&e| e >= -1e-12), "{ev:?}");
            if stretched {
                assert!((km - em).norm() < 1e-5, "{km} vs {em}");
            } else {
                // Exact block is indefinite; projection keeps its positive eigenpair (k n n^T).
                assert!(em.symmetric_eigen().eigenvalues.min() < 0.0);
                let n = nalgebra::Vector3::new(d[0], d[1], d[2]).normalize();
                assert!((km - n * n.transpose() * 7.0).norm() < 1e-12);
            }
        }
    }

    #[test]
    fn shear_and_bending_springs_on_quads() {
        let m = Mesh::new(
            (0..9)
                .map(|i| [(i % 3) as f64, (i / 3) as f64, 0.0])
                .collect(),
            vec![4; 4],
            vec![0, 1, 4, 3, 1, 2, 5, 4, 3, 4, 7, 6, 4, 5, 8, 7],
        )
        .unwrap();
        let none = SpringKinds {
            shear: false,
            bending: false,
            bending_scale: 1.0,
        };
        assert_eq!(springs_from_mesh(&m, 1.0, none).len(), 12);
        let shear = SpringKinds {
            shear: true,
            ..none
        };
        assert_eq!(springs_from_mesh(&m, 1.0, shear).len(), 20);
        let all = SpringKinds {
            bending: true,
            bending_scale: 0.5,
            ..shear
        };
        let s = springs_from_mesh(&m, 1.0, all);
        assert_eq!(s.len(), 26);
        assert!(s.ends.contains(&[0, 2]) && s.ends.contains(&[0, 6]));
        assert_eq!(s.k[s.ends.iter().position(|e| *e == [0, 2]).unwrap()], 0.5);
        assert!(!s.ends.contains(&[0, 8])); // a diagonal line is not a mesh line
    }
}
