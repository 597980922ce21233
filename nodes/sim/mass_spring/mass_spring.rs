//! The `mass_spring` node: cloth from a mesh (springs along edges, polygon diagonals and
//! optional bending lines), fixed vertices by selection, an optional sphere collider that
//! may move along keyframes, stepped frame by frame. The simulator is kept in the node's
//! state between frames and restarts when the mesh or any parameter changes.

use super::control::{pair_nearest, pairs_from_list, PairError};
use super::frame_run::{log_row, FrameRun, Params};
use super::implicit::NewtonOptions;
use super::keyframes::parse_keyframes;
use super::quasi_newton::QuasiNewtonOptions;
use super::simulator::{Method, SetupError, Simulator, SolverOptions};
use super::springs::{springs_from_mesh, Model, Sphere, SpringKinds, State};
use cgnodes_api::prelude::*;
use cgnodes_geometry::vertex_select::select_vertices;
use std::hash::{Hash, Hasher};

impl Choice for Method {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("implicit", Method::Implicit),
        ("semi_implicit", Method::SemiImplicit),
        ("projective", Method::Projective),
        ("quasi_newton", Method::QuasiNewton),
    ];
}

/// The axis gravity pulls along (the `gravity_axis` socket), as a coordinate index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct GravityAxis(usize);

impl Choice for GravityAxis {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("z", GravityAxis(2)),
        ("y", GravityAxis(1)),
        ("x", GravityAxis(0)),
    ];
}

/// The node's state between frames.
#[derive(Default)]
struct NodeState {
    sim: Option<Simulator>,
    key: u64,
    frame: i64,
    start_frame: i64,
    /// The body's positions at `frame` (control points), when a control mesh is linked.
    control_prev: Vec<[f64; 3]>,
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
    b.doc("Cloth as a mass-spring system: semi-implicit, implicit (Newton) or projective (Liu 2013) time steps, fixed vertices, sphere collider.");
    b.stateful();
    b.add_input::<Mesh>("mesh")
        .doc("Rest shape (e.g. the course's grid40x40.usda).");
    b.add_choice::<Method>("integrator");
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
    b.add_choice::<GravityAxis>("gravity_axis");
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
    b.add_input::<bool>("damped")
        .default(true)
        .doc("Apply `damping` (Framework3D's enable damping); off = undamped.");
    b.add_input::<Mesh>("control_mesh").optional().doc(
        "A moving body (e.g. the skinned arm), each frame: the fixed vertices follow its vertices (control points).",
    );
    b.add_input::<String>("control_select").default("").doc(
        "Body vertices the fixed vertices may pair with (selection as in `fixed`, e.g. attr:ControlPoints); empty = all.",
    );
    b.add_input::<Vec<i64>>("control_pairs").optional().doc(
        "Explicit pairs cloth, body, cloth, body, ... (these cloth vertices become fixed); else each fixed vertex pairs with the nearest selected body vertex at the start.",
    );
    b.add_input::<bool>("profile")
        .default(false)
        .doc("Logs each frame's wall time (Framework3D's enable time profiling).");
    b.add_input::<bool>("debug")
        .default(false)
        .doc("Logs each frame's energies and iterations (Framework3D's enable debug output).");
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
    let d = SolverOptions::default();
    b.add_input::<i64>("newton_iters")
        .default(d.newton.max_iters as i64)
        .range(1.0, 1000.0);
    b.add_input::<f64>("newton_tol")
        .default(d.newton.tol)
        .range(0.0, 1.0)
        .doc("Newton (and quasi_newton) stops when no vertex moves more than this.");
    b.add_input::<i64>("qn_iters")
        .default(d.quasi_newton.max_iters as i64)
        .range(1.0, 100000.0)
        .doc("Most L-BFGS iterations per step (quasi_newton).");
    b.add_input::<i64>("pd_iters")
        .default(d.pd_iterations as i64)
        .range(1.0, 10000.0)
        .doc("Local/global iterations per step (projective).");
    b.add_input::<f64>("blowup_factor")
        .default(d.blowup_factor)
        .range(1.0, 1e12)
        .doc("Energy growth (times the model's energy scale) reported as unstable.");
    b.add_output::<Mesh>("mesh");
    b.add_output::<Table>("log");
}

/// The scalar parameters of the dynamics, checked.
struct Dynamics {
    method: Method,
    k: f64,
    h: f64,
    substeps: i64,
    damping: f64,
    g: f64,
    axis: usize,
    mass: f64,
}

impl Dynamics {
    /// Reads and checks the scalar sockets (finite, positive step and mass, damping in (0, 1]).
    fn read(ctx: &ExecContext) -> Result<Dynamics, NodeError> {
        let method = ctx.choice::<Method>("integrator")?;
        let k: f64 = ctx.input("stiffness")?;
        let h: f64 = ctx.input("h")?;
        let substeps: i64 = ctx.input("substeps")?;
        let damping: f64 = ctx.input("damping")?;
        let g: f64 = ctx.input("gravity")?;
        let GravityAxis(axis) = ctx.choice::<GravityAxis>("gravity_axis")?;
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
        Ok(Dynamics {
            method,
            k,
            h,
            substeps,
            damping,
            g,
            axis,
            mass,
        })
    }

    /// The unit vector along gravity ("top" selections are against it; gravity 0 counts as
    /// down).
    fn down(&self) -> [f64; 3] {
        let mut down = [0.0; 3];
        down[self.axis] = if self.g > 0.0 { 1.0 } else { -1.0 };
        down
    }
}

/// The fixed flags from the `fixed` selection and the `fixed_indices` list.
fn fixed_vertices(ctx: &ExecContext, mesh: &Mesh, down: [f64; 3]) -> Result<Vec<bool>, NodeError> {
    let n = mesh.num_vertices();
    let mut fixed = vec![false; n];
    let sel: String = ctx.input("fixed")?;
    for i in select_vertices(mesh, &sel, down).map_err(|e| NodeError::invalid("fixed", e))? {
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
    Ok(fixed)
}

/// Control points: (cloth vertex, body vertex) pairs with the body, from `control_pairs`
/// (whose cloth vertices become fixed) or each fixed vertex with its nearest selected body
/// vertex.
fn control_pairs(
    ctx: &ExecContext,
    mesh: &Mesh,
    control: Option<&Mesh>,
    fixed: &mut [bool],
    down: [f64; 3],
) -> Result<Vec<(usize, usize)>, NodeError> {
    let n = mesh.num_vertices();
    let list = ctx.input_opt::<Vec<i64>>("control_pairs")?;
    let invalid =
        |socket: &'static str| move |e: PairError| NodeError::invalid(socket, e.to_string());
    match (control, list) {
        (None, Some(_)) => Err(NodeError::invalid(
            "control_pairs",
            "pairs need a control_mesh to follow",
        )),
        (None, None) => Ok(Vec::new()),
        (Some(body), Some(list)) => {
            let p =
                pairs_from_list(&list, n, body.num_vertices()).map_err(invalid("control_pairs"))?;
            for &(i, _) in &p {
                fixed[i] = true;
            }
            Ok(p)
        }
        (Some(body), None) => {
            let csel: String = ctx.input("control_select")?;
            let selected = if csel.trim().is_empty() {
                (0..body.num_vertices()).collect()
            } else {
                select_vertices(body, &csel, down)
                    .map_err(|e| NodeError::invalid("control_select", e))?
            };
            let fixed_list: Vec<usize> = (0..n).filter(|&i| fixed[i]).collect();
            pair_nearest(&mesh.positions, &fixed_list, &body.positions, &selected)
                .map_err(invalid("control_select"))
        }
    }
}

/// The sphere collider when `sphere` is on (its parameters checked finite).
fn sphere_collider(ctx: &ExecContext) -> Result<Option<Sphere>, NodeError> {
    if !ctx.input::<bool>("sphere")? {
        return Ok(None);
    }
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
    Ok(Some(Sphere {
        center: c,
        radius: r,
        k: kp,
        scale: s,
    }))
}

/// Newton and projective iteration settings and the blow-up threshold.
fn solver_options(ctx: &ExecContext) -> Result<SolverOptions, NodeError> {
    Ok(SolverOptions {
        newton: NewtonOptions {
            max_iters: ctx.input::<i64>("newton_iters")?.max(1) as usize,
            tol: ctx.input("newton_tol")?,
            ..NewtonOptions::default()
        },
        quasi_newton: QuasiNewtonOptions {
            max_iters: ctx.input::<i64>("qn_iters")?.max(1) as usize,
            tol: ctx.input("newton_tol")?,
            ..QuasiNewtonOptions::default()
        },
        pd_iterations: ctx.input::<i64>("pd_iters")?.max(1) as usize,
        blowup_factor: ctx.input("blowup_factor")?,
    })
}

/// Reads the parameters; builds the simulator (springs, factorizations) only when `with_sim`.
fn build(
    ctx: &ExecContext,
    mesh: &Mesh,
    control: Option<&Mesh>,
    with_sim: bool,
) -> Result<(Option<Simulator>, Params), NodeError> {
    let dy = Dynamics::read(ctx)?;
    let n = mesh.num_vertices();
    if n == 0 {
        return Err(NodeError::topology("mesh", "the mesh has no vertices"));
    }
    let kinds = SpringKinds {
        shear: ctx.input("shear")?,
        bending: ctx.input("bending")?,
        bending_scale: 1.0,
    };
    let springs = springs_from_mesh(mesh, dy.k, kinds);
    let down = dy.down();
    let mut fixed = fixed_vertices(ctx, mesh, down)?;
    // Control points: pairs with the body, whose cloth vertices are fixed and start on it.
    let pairs = control_pairs(ctx, mesh, control, &mut fixed, down)?;
    let mut x0 = mesh.positions.clone();
    if let Some(body) = control {
        for &(i, j) in &pairs {
            x0[i] = body.positions[j];
        }
    }
    let mut gravity = [0.0; 3];
    gravity[dy.axis] = dy.g;
    let model = Model {
        springs,
        mass: vec![dy.mass / n as f64; n],
        fixed,
        gravity,
        // The course applies `damping` once per step of h = 0.01; scaling it to the step keeps
        // the same decay per second whatever h and substeps are.
        damping: if ctx.input::<bool>("damped")? {
            dy.damping.powf(dy.h / 0.01)
        } else {
            1.0
        },
    };
    let sphere = sphere_collider(ctx)?;
    let keys = parse_keyframes(&ctx.input::<String>("sphere_keyframes")?)
        .map_err(|e| NodeError::invalid("sphere_keyframes", e))?;
    let opts = solver_options(ctx)?;
    let sim = if with_sim {
        Some(
            Simulator::new(model, x0, None, dy.method, dy.h, opts).map_err(|e| match e {
                SetupError::NotPositiveDefinite(m) => NodeError::singular(m),
                SetupError::Invalid(m) => NodeError::invalid("mesh", m),
                SetupError::Model(e) => NodeError::invalid("mesh", e.to_string()),
            })?,
        )
    } else {
        None
    };
    Ok((
        sim,
        Params {
            method: dy.method,
            h: dy.h,
            substeps: dy.substeps.max(1) as usize,
            sphere,
            keys,
            pairs,
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
    // The body moves every frame and the logging switches change nothing: neither restarts.
    for s in &ctx.decl.inputs {
        if !["mesh", "control_mesh", "profile", "debug"].contains(&s.name.as_str()) {
            s.name.hash(&mut h);
            if let Some(v) = ctx.input_value(&s.name) {
                v.to_json().map(|j| j.to_string()).hash(&mut h);
            }
        }
    }
    h.finish()
}

/// The body's positions this frame (empty without a control mesh); `Err` when its vertex
/// count changed since the simulation started.
fn control_pose(control: Option<&Mesh>, started_with: usize) -> Result<Vec<[f64; 3]>, NodeError> {
    match control {
        Some(c) => {
            if c.num_vertices() != started_with {
                return Err(NodeError::invalid(
                    "control_mesh",
                    format!(
                        "{} vertices; it had {} when the simulation started",
                        c.num_vertices(),
                        started_with
                    ),
                ));
            }
            Ok(c.positions.clone())
        }
        None => Ok(Vec::new()),
    }
}

/// The output mesh: the input with the simulated positions and a `velocity` attribute.
fn simulated_mesh(mesh: &Mesh, state: State) -> Mesh {
    let mut out = mesh.clone();
    out.positions = state.x;
    out.attributes.insert(
        "velocity".into(),
        AttributeData::Vec3(Attribute {
            domain: Domain::Vertex,
            values: state.v,
        }),
    );
    out
}

/// The `debug` log line: the last logged row's energies and iterations.
fn debug_line(log: &Table, frame: i64) -> String {
    let row = log.num_rows().saturating_sub(1);
    let col = |c: &str| {
        log.column(c)
            .and_then(|v| v.get(row).copied())
            .unwrap_or(0.0)
    };
    format!(
        "frame {frame}: kinetic {:.4e}, potential {:.4e}, max strain {:.3e}, iterations {}",
        col("kinetic"),
        col("potential"),
        col("max_strain"),
        col("iterations")
    )
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let started = std::time::Instant::now();
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let control = ctx.input_opt::<Arc<Mesh>>("control_mesh")?;
    let key = input_key(ctx, &mesh);
    let frame = ctx.frame();
    let restart = {
        let st = ctx.state::<NodeState>()?;
        st.sim.is_none() || st.key != key || frame <= st.frame
    };
    let (sim0, params) = build(ctx, &mesh, control.as_deref(), restart)?;
    let (profile, debug): (bool, bool) = (ctx.input("profile")?, ctx.input("debug")?);
    let progress = ctx.progress_fn();
    let st = ctx.state::<NodeState>()?;
    let mut log = Table::with_columns(&LOG_COLUMNS);
    if let Some(sim0) = sim0 {
        // First frame (or new input): the rest state, no steps.
        let e = sim0.energy(params.sphere.as_ref());
        log.push_row(&log_row(frame, 0.0, 0.0, &e, 0.0));
        *st = NodeState {
            sim: Some(sim0),
            key,
            frame,
            start_frame: frame,
            control_prev: control
                .as_ref()
                .map(|c| c.positions.clone())
                .unwrap_or_default(),
        };
    }
    let cur = control_pose(control.as_deref(), st.control_prev.len())?;
    let run = FrameRun {
        params: &params,
        start: st.start_frame,
        last: st.frame,
        frames: (frame - st.frame).max(0) as usize,
        control_prev: &st.control_prev,
        control_cur: &cur,
    };
    let sim = st.sim.as_mut().expect("set above");
    if let Err(e) = run.advance(sim, &mut log, &progress) {
        ctx.reset_state();
        return Err(e);
    }
    let state = sim.state.clone();
    st.frame = frame;
    if control.is_some() {
        st.control_prev = cur;
    }
    let out = simulated_mesh(&mesh, state);
    log.meta
        .insert("integrator".into(), format!("{:?}", params.method));
    if debug {
        ctx.log(debug_line(&log, frame));
    }
    if profile {
        ctx.log(format!(
            "frame took {:.1} ms",
            started.elapsed().as_secs_f64() * 1e3
        ));
    }
    ctx.set_output("mesh", out);
    ctx.set_output("log", log);
    Ok(())
}

/// Registers `mass_spring`.
pub fn register(r: &mut Registry) {
    r.add("mass_spring", declare, execute);
}
