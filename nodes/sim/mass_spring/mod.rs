//! `mass_spring`: cloth as a mass-spring system (course assignment 8), stepped frame by frame
//! with one of three integrators: `semi_implicit` (symplectic Euler, conditionally stable),
//! `implicit` (backward Euler by Newton's method on its variational form, stable at large
//! steps) or `projective` (Liu et al. 2013's local/global solver with a prefactored matrix).
//!
//! The core is plain data (`Model`, `State`) and a `Simulator` that advances it step by step
//! and detects blow-ups; the node wraps it with frame-to-frame state, fixed-vertex
//! selections and a sphere collider that may move along keyframes.

// Numerical kernels index several parallel arrays (positions, velocities, masses, flags) by
// vertex; index loops read closer to the formulas than zipped iterators.
#![allow(clippy::needless_range_loop)]

/// Moved to `nodes::mesh::mesh_grid`; kept under the old path for its importers.
pub use crate::nodes::mesh::mesh_grid as grid;
pub mod implicit;
pub mod projective;
pub mod semi_implicit;
pub mod springs;

use crate::prelude::*;
pub use implicit::{Implicit, NewtonOptions};
pub use projective::Projective;
pub use semi_implicit::SemiImplicit;
pub use springs::{energy, springs_from_mesh, Energy, Model, Sphere, SpringKinds, Springs, State};
use std::hash::{Hash, Hasher};

/// Which time integrator advances the system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Symplectic Euler.
    SemiImplicit,
    /// Backward Euler by Newton's method.
    Implicit,
    /// Liu et al. 2013 local/global.
    Projective,
}

impl Method {
    /// Parses `semi_implicit`, `implicit` or `projective`.
    pub fn parse(s: &str) -> Option<Method> {
        match s {
            "semi_implicit" => Some(Method::SemiImplicit),
            "implicit" => Some(Method::Implicit),
            "projective" => Some(Method::Projective),
            _ => None,
        }
    }
}

/// Solver settings beyond the model.
#[derive(Clone, Copy, Debug)]
pub struct SolverOptions {
    /// Newton options (implicit).
    pub newton: NewtonOptions,
    /// Local/global iterations per step (projective).
    pub pd_iterations: usize,
    /// A step is reported unstable when the total energy exceeds its initial value by more
    /// than this factor times the model's energy scale (see `energy_scale`).
    pub blowup_factor: f64,
}

impl Default for SolverOptions {
    fn default() -> Self {
        SolverOptions {
            newton: NewtonOptions::default(),
            pd_iterations: 10,
            blowup_factor: 100.0,
        }
    }
}

enum Solver {
    Semi(SemiImplicit),
    Implicit(Box<Implicit>),
    Projective(Box<Projective>),
}

/// What one step did.
#[derive(Clone, Copy, Debug, Default)]
pub struct StepLog {
    /// Energies after the step.
    pub energy: Energy,
    /// Newton iterations (implicit), local/global iterations (projective), 0 otherwise.
    pub iterations: usize,
}

/// Why a step failed.
#[derive(Clone, Debug, PartialEq)]
pub enum SimError {
    /// NaN, infinity or runaway energy at step `step` (0-based count of steps taken).
    Unstable {
        /// The step that blew up.
        step: usize,
        /// What was seen.
        reason: String,
    },
    /// A linear solve failed.
    Solver(String),
}

/// The energy a healthy run stays within: `M |g| D + sum_s 1/2 k_s (0.1 L_s)^2` (falling by the
/// model's size `D`, stretching every spring by 10 %), plus the initial kinetic energy.
pub fn energy_scale(m: &Model, x: &[[f64; 3]], e0: &Energy) -> f64 {
    let (lo, hi) = bounds(x);
    let diag = springs::norm(springs::sub(hi, lo));
    let mass: f64 = m.mass.iter().sum();
    let g = springs::norm(m.gravity);
    let spring: f64 = (0..m.springs.len())
        .map(|s| 0.5 * m.springs.k[s] * (0.1 * m.springs.rest[s]).powi(2))
        .sum();
    mass * g * diag + spring + e0.kinetic.abs() + e0.potential.abs()
}

fn bounds(x: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in x {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    if x.is_empty() {
        ([0.0; 3], [0.0; 3])
    } else {
        (lo, hi)
    }
}

/// Advances a `Model` step by step with one integrator and watches for blow-ups.
pub struct Simulator {
    /// The dynamics.
    pub model: Model,
    /// Current positions and velocities.
    pub state: State,
    /// Positions gravity's potential energy is measured from.
    pub x_ref: Vec<[f64; 3]>,
    /// Time step.
    pub h: f64,
    /// Steps taken.
    pub steps: usize,
    /// The integrator.
    pub method: Method,
    solver: Solver,
    e0: f64,
    e_limit: f64,
}

impl Simulator {
    /// A simulator starting at `x0` with velocities `v0` (zero when `None`).
    pub fn new(
        model: Model,
        x0: Vec<[f64; 3]>,
        v0: Option<Vec<[f64; 3]>>,
        method: Method,
        h: f64,
        opts: SolverOptions,
    ) -> Result<Simulator, String> {
        model.check()?;
        let n = model.num_vertices();
        if x0.len() != n {
            return Err(format!("{} positions for {n} vertices", x0.len()));
        }
        if !(h.is_finite() && h > 0.0) {
            return Err(format!("time step {h} must be positive"));
        }
        let v = v0.unwrap_or_else(|| vec![[0.0; 3]; n]);
        if v.len() != n {
            return Err(format!("{} velocities for {n} vertices", v.len()));
        }
        let solver = match method {
            Method::SemiImplicit => Solver::Semi(SemiImplicit::new(&model)),
            Method::Implicit => Solver::Implicit(Box::new(Implicit::new(&model, opts.newton)?)),
            Method::Projective => {
                Solver::Projective(Box::new(Projective::new(&model, h, opts.pd_iterations)?))
            }
        };
        let state = State { x: x0.clone(), v };
        let e = energy(&model, &state, &x0, None);
        let scale = energy_scale(&model, &x0, &e);
        Ok(Simulator {
            e0: e.total(),
            e_limit: opts.blowup_factor * scale,
            model,
            state,
            x_ref: x0,
            h,
            steps: 0,
            method,
            solver,
        })
    }

    /// Energy of the current state.
    pub fn energy(&self, sphere: Option<&Sphere>) -> Energy {
        energy(&self.model, &self.state, &self.x_ref, sphere)
    }

    /// Number of symbolic and numeric factorizations so far (implicit only).
    pub fn factorizations(&self) -> Option<(usize, usize)> {
        match &self.solver {
            Solver::Implicit(s) => Some((s.symbolic_count, s.numeric_count)),
            _ => None,
        }
    }

    /// One step of length `h` with the collider at `sphere` (its position at the step's end),
    /// then the energy check: fails with `Unstable` on NaN, infinity or runaway energy.
    pub fn step(&mut self, sphere: Option<&Sphere>) -> Result<StepLog, SimError> {
        let iterations = self.advance(sphere)?;
        let energy = self.check_energy(sphere)?;
        Ok(StepLog { energy, iterations })
    }

    /// One step without the energy check (only NaN and infinity are caught); returns the
    /// iterations. For callers that check energy less often (`check_energy`), e.g. once per
    /// frame in benchmarks.
    pub fn advance(&mut self, sphere: Option<&Sphere>) -> Result<usize, SimError> {
        let h = self.h;
        let step = self.steps;
        let iterations = match &mut self.solver {
            Solver::Semi(s) => {
                s.step(&self.model, &mut self.state, h, sphere);
                0
            }
            Solver::Implicit(s) => {
                s.step(&self.model, &mut self.state, h, sphere)
                    .map_err(|e| match e.contains("finite") {
                        true => SimError::Unstable { step, reason: e },
                        false => SimError::Solver(e),
                    })?
            }
            Solver::Projective(s) => s.step(&self.model, &mut self.state, sphere),
        };
        self.steps += 1;
        if let Some(i) = (0..self.state.x.len()).find(|&i| {
            self.state.x[i]
                .iter()
                .chain(&self.state.v[i])
                .any(|c| !c.is_finite())
        }) {
            return Err(SimError::Unstable {
                step,
                reason: format!("vertex {i} is not finite"),
            });
        }
        Ok(iterations)
    }

    /// The current energy, or `Unstable` when the total exceeds the initial energy by more
    /// than the blow-up threshold.
    pub fn check_energy(&self, sphere: Option<&Sphere>) -> Result<Energy, SimError> {
        let e = self.energy(sphere);
        if !e.total().is_finite() || e.total() - self.e0 > self.e_limit {
            return Err(SimError::Unstable {
                step: self.steps.saturating_sub(1),
                reason: format!(
                    "total energy {:.4e} exceeds the initial {:.4e} by more than {:.4e}",
                    e.total(),
                    self.e0,
                    self.e_limit
                ),
            });
        }
        Ok(e)
    }
}

/// Vertices named by a selection: `""`/`none`, a list of indices (`"0,39"` or `"0 39"`),
/// `top_corners`, `top_edge`, `corners`, or `attr:NAME` (a vertex attribute, nonzero = selected).
/// "Top" is against gravity when the mesh extends along it, else along the in-plane axis
/// with the largest extent (y first), so the course's xy grids hang from their y = 1 side.
pub fn select_vertices(mesh: &Mesh, sel: &str, gravity_axis: usize) -> Result<Vec<usize>, String> {
    let sel = sel.trim();
    let n = mesh.num_vertices();
    if sel.is_empty() || sel == "none" {
        return Ok(Vec::new());
    }
    let tokens: Vec<&str> = sel
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .collect();
    if tokens.iter().all(|t| t.parse::<i64>().is_ok()) {
        let mut out = Vec::new();
        for t in tokens {
            let i: i64 = t.parse().unwrap_or(-1);
            if i < 0 || i as usize >= n {
                return Err(format!("vertex index {i} is outside 0..{n}"));
            }
            out.push(i as usize);
        }
        return Ok(out);
    }
    if let Some(name) = sel.strip_prefix("attr:") {
        let a = mesh
            .attributes
            .get(name)
            .ok_or_else(|| format!("the mesh has no attribute '{name}'"))?;
        let vals: Vec<f64> = match a {
            AttributeData::Float(a) if a.domain == Domain::Vertex => a.values.clone(),
            AttributeData::Int(a) if a.domain == Domain::Vertex => {
                a.values.iter().map(|&v| v as f64).collect()
            }
            _ => return Err(format!("attribute '{name}' is not a per-vertex number")),
        };
        return Ok((0..n)
            .filter(|&i| vals.get(i).is_some_and(|v| *v != 0.0))
            .collect());
    }
    if n == 0 {
        return Ok(Vec::new());
    }
    let (lo, hi) = mesh.bounds();
    let ext = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
    let diag = (ext[0] * ext[0] + ext[1] * ext[1] + ext[2] * ext[2]).sqrt();
    let tol = 1e-6 * diag.max(1e-300);
    let g = gravity_axis.min(2);
    let (top, top_sign) = if ext[g] > 1e-3 * diag {
        (g, 1.0)
    } else {
        let mut best = None;
        for a in [1usize, 2, 0] {
            if a != g && best.is_none_or(|b: usize| ext[a] > ext[b] + tol) {
                best = Some(a);
            }
        }
        (best.unwrap_or(1), 1.0)
    };
    // The side axis: the largest remaining extent, never the gravity axis.
    let side = (0..3)
        .filter(|&a| a != top && a != g)
        .max_by(|&a, &b| ext[a].total_cmp(&ext[b]))
        .unwrap_or((top + 1) % 3);
    let t = |i: usize| top_sign * mesh.positions[i][top];
    let u = |i: usize| mesh.positions[i][side];
    let (et, eu) = (ext[top].max(1e-300), ext[side].max(1e-300));
    let argmax =
        |f: &dyn Fn(usize) -> f64| (0..n).max_by(|&a, &b| f(a).total_cmp(&f(b))).unwrap_or(0);
    match sel {
        "top_edge" => {
            let tmax = (0..n).map(t).fold(f64::NEG_INFINITY, f64::max);
            Ok((0..n).filter(|&i| t(i) >= tmax - tol).collect())
        }
        "top_corners" => {
            let a = argmax(&|i| t(i) / et + u(i) / eu);
            let b = argmax(&|i| t(i) / et - u(i) / eu);
            Ok(if a == b { vec![a] } else { vec![a, b] })
        }
        "corners" => {
            let mut out = Vec::new();
            for (st, su) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                let c = argmax(&|i| st * t(i) / et + su * u(i) / eu);
                if !out.contains(&c) {
                    out.push(c);
                }
            }
            Ok(out)
        }
        other => Err(format!(
            "'{other}' is not a selection: use indices like \"0,39\", top_corners, top_edge, corners, attr:NAME or none"
        )),
    }
}

/// Sphere centre at fractional frame `f` from keyframes `"frame:x,y,z; frame:x,y,z"`
/// (linear between keys, held outside them); `None` when there are no keys.
pub fn keyframed_center(keys: &[(f64, [f64; 3])], f: f64) -> Option<[f64; 3]> {
    let first = keys.first()?;
    if f <= first.0 {
        return Some(first.1);
    }
    for w in keys.windows(2) {
        let ((f0, c0), (f1, c1)) = (w[0], w[1]);
        if f <= f1 {
            let s = if f1 > f0 { (f - f0) / (f1 - f0) } else { 1.0 };
            return Some(springs::axpy(c0, s, springs::sub(c1, c0)));
        }
    }
    keys.last().map(|k| k.1)
}

/// Parses `"frame:x,y,z; frame:x,y,z"` keyframes, sorted by frame.
pub fn parse_keyframes(s: &str) -> Result<Vec<(f64, [f64; 3])>, String> {
    let mut out = Vec::new();
    for part in s.split(';').map(str::trim).filter(|p| !p.is_empty()) {
        let (f, c) = part
            .split_once(':')
            .ok_or_else(|| format!("keyframe '{part}' is not 'frame:x,y,z'"))?;
        let f: f64 = f
            .trim()
            .parse()
            .map_err(|_| format!("keyframe '{part}': bad frame"))?;
        let c: Vec<f64> = c
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("keyframe '{part}': bad coordinates"))?;
        if c.len() != 3 || !f.is_finite() || c.iter().any(|x| !x.is_finite()) {
            return Err(format!(
                "keyframe '{part}' needs a frame and 3 finite numbers"
            ));
        }
        out.push((f, [c[0], c[1], c[2]]));
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(out)
}

/// The node's state between frames.
#[derive(Default)]
struct NodeState {
    sim: Option<Simulator>,
    key: u64,
    frame: i64,
    start_frame: i64,
}

/// Columns of the `log` table.
pub const LOG_COLUMNS: [&str; 8] = [
    "frame",
    "step",
    "time",
    "kinetic",
    "potential",
    "total",
    "max_strain",
    "iterations",
];

fn declare(b: &mut NodeBuilder) {
    b.doc("Cloth as a mass-spring system: semi-implicit, implicit (Newton) or projective (Liu 2013) time steps, fixed vertices, sphere collider.")
        .category("sim");
    b.stateful();
    b.add_input::<Mesh>("mesh")
        .doc("Rest shape (e.g. the course's grid40x40.usda).");
    b.add_input::<String>("integrator")
        .choices(&["implicit", "semi_implicit", "projective"]);
    b.add_input::<f64>("stiffness")
        .default(1000.0)
        .range(0.0, 1e9);
    b.add_input::<f64>("h")
        .default(0.01)
        .range(1e-7, 0.5)
        .doc("Time step (s).");
    b.add_input::<i64>("substeps")
        .default(1i64)
        .range(1.0, 100000.0)
        .doc("Steps per frame.");
    b.add_input::<f64>("damping")
        .default(0.995)
        .range(1e-6, 1.0)
        .doc("Velocity factor per 0.01 s (per step at the course's h = 0.01; 1 = undamped).");
    b.add_input::<f64>("gravity").default(-9.8).range(-1e4, 1e4);
    b.add_input::<String>("gravity_axis")
        .choices(&["z", "y", "x"]);
    b.add_input::<f64>("mass")
        .default(1.0)
        .min(1e-12)
        .doc("Total mass, spread equally over the vertices (as in the course).");
    b.add_input::<bool>("shear")
        .default(true)
        .doc("Springs across polygon diagonals (quads).");
    b.add_input::<bool>("bending")
        .default(false)
        .doc("Skip-one springs along straight mesh lines.");
    b.add_input::<String>("fixed").default("").doc(
        "Fixed vertices: indices \"0,39\", top_corners, top_edge, corners, attr:NAME, or empty.",
    );
    b.add_input::<Vec<i64>>("fixed_indices")
        .optional()
        .doc("More fixed vertex indices.");
    b.add_input::<bool>("sphere")
        .default(false)
        .doc("Enable the sphere collider.");
    b.add_input::<[f64; 3]>("sphere_center")
        .default([0.0, 0.0, -1.0]);
    b.add_input::<f64>("sphere_radius")
        .default(0.4)
        .range(0.0, 1e6);
    b.add_input::<f64>("penalty_k")
        .default(10000.0)
        .range(0.0, 1e12);
    b.add_input::<f64>("collision_scale")
        .default(1.1)
        .range(1.0, 10.0)
        .doc("Contact starts at this factor times the radius (course: 1.1).");
    b.add_input::<String>("sphere_keyframes")
        .default("")
        .doc("Moving sphere: \"frame:x,y,z; frame:x,y,z\" (overrides sphere_center).");
    b.add_input::<i64>("newton_iters")
        .default(20i64)
        .range(1.0, 1000.0);
    b.add_input::<f64>("newton_tol")
        .default(1e-7)
        .range(0.0, 1.0)
        .doc("Newton stops when no vertex moves more than this.");
    b.add_input::<i64>("pd_iters")
        .default(10i64)
        .range(1.0, 10000.0)
        .doc("Local/global iterations per step (projective).");
    b.add_input::<f64>("blowup_factor")
        .default(100.0)
        .range(1.0, 1e12)
        .doc("Energy growth (times the model's energy scale) reported as unstable.");
    b.add_output::<Mesh>("mesh");
    b.add_output::<Table>("log");
}

struct Params {
    method: Method,
    h: f64,
    substeps: usize,
    sphere: Option<Sphere>,
    keys: Vec<(f64, [f64; 3])>,
}

/// Reads the parameters; builds the simulator (springs, factorizations) only when `with_sim`.
fn build(
    ctx: &ExecContext,
    mesh: &Mesh,
    with_sim: bool,
) -> Result<(Option<Simulator>, Params), NodeError> {
    let method = Method::parse(&ctx.input::<String>("integrator")?)
        .ok_or_else(|| NodeError::invalid("integrator", "unknown integrator"))?;
    let k: f64 = ctx.input("stiffness")?;
    let h: f64 = ctx.input("h")?;
    let substeps: i64 = ctx.input("substeps")?;
    let damping: f64 = ctx.input("damping")?;
    let g: f64 = ctx.input("gravity")?;
    let axis = match ctx.input::<String>("gravity_axis")?.as_str() {
        "x" => 0,
        "y" => 1,
        _ => 2,
    };
    let mass: f64 = ctx.input("mass")?;
    for (name, v) in [
        ("stiffness", k),
        ("h", h),
        ("damping", damping),
        ("gravity", g),
        ("mass", mass),
    ] {
        if !v.is_finite() {
            return Err(NodeError::invalid(name, "must be finite"));
        }
    }
    if h <= 0.0 {
        return Err(NodeError::invalid("h", "must be positive"));
    }
    if mass <= 0.0 {
        return Err(NodeError::invalid("mass", "must be positive"));
    }
    if !(damping > 0.0 && damping <= 1.0) {
        return Err(NodeError::invalid("damping", "must be in (0, 1]"));
    }
    let n = mesh.num_vertices();
    if n == 0 {
        return Err(NodeError::topology("mesh", "the mesh has no vertices"));
    }
    let kinds = SpringKinds {
        shear: ctx.input("shear")?,
        bending: ctx.input("bending")?,
        bending_scale: 1.0,
    };
    let springs = springs_from_mesh(mesh, k, kinds);
    let mut fixed = vec![false; n];
    let sel: String = ctx.input("fixed")?;
    for i in select_vertices(mesh, &sel, axis).map_err(|e| NodeError::invalid("fixed", e))? {
        fixed[i] = true;
    }
    if let Some(list) = ctx.input_opt::<Vec<i64>>("fixed_indices")? {
        for i in list {
            if i < 0 || i as usize >= n {
                return Err(NodeError::invalid(
                    "fixed_indices",
                    format!("vertex index {i} is outside 0..{n}"),
                ));
            }
            fixed[i as usize] = true;
        }
    }
    let mut gravity = [0.0; 3];
    gravity[axis] = g;
    let model = Model {
        springs,
        mass: vec![mass / n as f64; n],
        fixed,
        gravity,
        // The course applies `damping` once per step of h = 0.01; scaling it to the step keeps
        // the same decay per second whatever h and substeps are.
        damping: damping.powf(h / 0.01),
    };
    let sphere = if ctx.input::<bool>("sphere")? {
        let r: f64 = ctx.input("sphere_radius")?;
        let kp: f64 = ctx.input("penalty_k")?;
        let s: f64 = ctx.input("collision_scale")?;
        let c: [f64; 3] = ctx.input("sphere_center")?;
        if !(r.is_finite() && kp.is_finite() && s.is_finite() && c.iter().all(|x| x.is_finite())) {
            return Err(NodeError::invalid(
                "sphere_radius",
                "sphere parameters must be finite",
            ));
        }
        Some(Sphere {
            center: c,
            radius: r,
            k: kp,
            scale: s,
        })
    } else {
        None
    };
    let keys = parse_keyframes(&ctx.input::<String>("sphere_keyframes")?)
        .map_err(|e| NodeError::invalid("sphere_keyframes", e))?;
    let opts = SolverOptions {
        newton: NewtonOptions {
            max_iters: ctx.input::<i64>("newton_iters")?.max(1) as usize,
            tol: ctx.input("newton_tol")?,
        },
        pd_iterations: ctx.input::<i64>("pd_iters")?.max(1) as usize,
        blowup_factor: ctx.input("blowup_factor")?,
    };
    let sim = if with_sim {
        Some(
            Simulator::new(model, mesh.positions.clone(), None, method, h, opts).map_err(|e| {
                match e.contains("positive definite") {
                    true => NodeError::singular(e),
                    false => NodeError::invalid("mesh", e),
                }
            })?,
        )
    } else {
        None
    };
    Ok((
        sim,
        Params {
            method,
            h,
            substeps: substeps.max(1) as usize,
            sphere,
            keys,
        },
    ))
}

/// A hash of the mesh and every parameter: when it changes, the simulation restarts.
fn input_key(ctx: &ExecContext, mesh: &Mesh) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for p in &mesh.positions {
        for c in p {
            c.to_bits().hash(&mut h);
        }
    }
    mesh.face_counts().hash(&mut h);
    mesh.face_indices().hash(&mut h);
    for s in &ctx.decl.inputs {
        if s.name != "mesh" {
            s.name.hash(&mut h);
            if let Some(v) = ctx.input_value(&s.name) {
                v.to_json().map(|j| j.to_string()).hash(&mut h);
            }
        }
    }
    h.finish()
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let key = input_key(ctx, &mesh);
    let frame = ctx.frame();
    let restart = {
        let st = ctx.state::<NodeState>()?;
        st.sim.is_none() || st.key != key || frame <= st.frame
    };
    let (sim0, params) = build(ctx, &mesh, restart)?;
    let st = ctx.state::<NodeState>()?;
    let mut log = Table::with_columns(&LOG_COLUMNS);
    if let Some(sim0) = sim0 {
        // First frame (or new input): the rest state, no steps.
        let e = sim0.energy(params.sphere.as_ref());
        log.push_row(&[
            frame as f64,
            0.0,
            0.0,
            e.kinetic,
            e.potential,
            e.total(),
            e.max_strain,
            0.0,
        ]);
        st.sim = Some(sim0);
        st.key = key;
        st.frame = frame;
        st.start_frame = frame;
    }
    let start = st.start_frame;
    let frames = (frame - st.frame).max(0) as usize;
    let last = st.frame;
    let result = {
        let sim = st.sim.as_mut().expect("set above");
        let mut err = None;
        'outer: for df in 0..frames {
            let f = last + df as i64; // frame being advanced from
            for s in 0..params.substeps {
                let frac = (f - start) as f64 + (s + 1) as f64 / params.substeps as f64;
                let sphere = params.sphere.map(|mut sp| {
                    if let Some(c) = keyframed_center(&params.keys, start as f64 + frac) {
                        sp.center = c;
                    }
                    sp
                });
                match sim.step(sphere.as_ref()) {
                    Ok(l) => log.push_row(&[
                        (f + 1) as f64,
                        sim.steps as f64,
                        sim.steps as f64 * params.h,
                        l.energy.kinetic,
                        l.energy.potential,
                        l.energy.total(),
                        l.energy.max_strain,
                        l.iterations as f64,
                    ]),
                    Err(e) => {
                        err = Some(match e {
                            SimError::Unstable { reason, .. } => NodeError::unstable(format!(
                                "{:?} integrator blew up at frame {} step {} (h = {}): {reason}; use a smaller h, more substeps, or the implicit integrator",
                                params.method, f + 1, s + 1, params.h
                            )),
                            SimError::Solver(m) => NodeError::singular(format!(
                                "frame {} step {}: {m}",
                                f + 1,
                                s + 1
                            )),
                        });
                        break 'outer;
                    }
                }
            }
        }
        match err {
            Some(e) => Err(e),
            None => Ok(sim.state.clone()),
        }
    };
    let state = match result {
        Ok(s) => s,
        Err(e) => {
            ctx.reset_state();
            return Err(e);
        }
    };
    st.frame = frame;
    let mut out = (*mesh).clone();
    out.positions = state.x;
    out.attributes.insert(
        "velocity".into(),
        AttributeData::Vec3(Attribute {
            domain: Domain::Vertex,
            values: state.v,
        }),
    );
    log.meta
        .insert("integrator".into(), format!("{:?}", params.method));
    ctx.set_output("mesh", out);
    ctx.set_output("log", log);
    Ok(())
}

/// Registers `mass_spring`.
pub fn register(r: &mut Registry) {
    r.add("mass_spring", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn selections() {
        let m = grid::grid_mesh(10, 10, [2.0, 2.0], "xy", [0.0; 3], true).unwrap();
        assert_eq!(
            select_vertices(&m, "top_corners", 2).unwrap(),
            vec![120, 110]
        );
        assert_eq!(select_vertices(&m, "0, 39", 2).unwrap(), vec![0, 39]);
        assert_eq!(
            select_vertices(&m, "top_edge", 2).unwrap(),
            (110..121).collect::<Vec<_>>()
        );
        let mut c = select_vertices(&m, "corners", 2).unwrap();
        c.sort();
        assert_eq!(c, vec![0, 10, 110, 120]);
        assert!(select_vertices(&m, "", 2).unwrap().is_empty());
        assert!(select_vertices(&m, "121", 2).is_err());
        // A vertical cloth (xz plane) hangs from its highest side along gravity (z).
        let v = grid::grid_mesh(4, 4, [1.0, 1.0], "xz", [0.0; 3], false).unwrap();
        assert_eq!(select_vertices(&v, "top_corners", 2).unwrap(), vec![24, 20]);
        let mut a = m.clone();
        let vals = (0..121).map(|i| if i == 5 { 1.0 } else { 0.0 }).collect();
        a.attributes.insert(
            "pin".into(),
            AttributeData::Float(Attribute {
                domain: Domain::Vertex,
                values: vals,
            }),
        );
        assert_eq!(select_vertices(&a, "attr:pin", 2).unwrap(), vec![5]);
    }

    #[test]
    fn keyframes_interpolate_linearly() {
        let k = parse_keyframes("10: 0,0,1; 0:0,0,-1").unwrap();
        assert_eq!(keyframed_center(&k, -3.0), Some([0.0, 0.0, -1.0]));
        assert_eq!(keyframed_center(&k, 5.0), Some([0.0, 0.0, 0.0]));
        assert_eq!(keyframed_center(&k, 20.0), Some([0.0, 0.0, 1.0]));
        assert_eq!(keyframed_center(&[], 1.0), None);
        assert!(parse_keyframes("1:0,0").is_err());
        assert!(parse_keyframes("x:0,0,0").is_err());
    }
}
