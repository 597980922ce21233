//! `sph_fluid`: Framework3D's `geom_sph_fluid` as a stateful node. Each execution advances
//! the fluid by one frame (`frame_dt`, in steps of `dt` or adaptive CFL steps) and outputs
//! the particles, an image of them coloured by speed, the run log and the dam-break front
//! history in Martin & Moyce's dimensionless units. The state restarts on the first frame,
//! when the frame goes backwards, or when any parameter changes.

use super::neighbour_grid::GridError;
use super::state::{Boundary, Fluid, Solver, SphParams};
use super::time_step::AdvanceError;
use cgnodes_api::prelude::*;
use cgnodes_api::types::vec3::dot;

/// The particles as `Points` with `velocity`, `density`, `pressure`, `speed` and `color`.
pub fn to_points(f: &Fluid, vref: f64) -> Points {
    let mut pts = Points {
        dim: f.params.dim as u8,
        positions: f.positions.clone(),
        ..Default::default()
    };
    let speed: Vec<f64> = f.velocities.iter().map(|v| dot(*v, *v).sqrt()).collect();
    pts.vectors.insert(
        "color".into(),
        speed.iter().map(|s| speed_color(s / vref)).collect(),
    );
    pts.vectors.insert("velocity".into(), f.velocities.clone());
    pts.scalars.insert("density".into(), f.densities.clone());
    pts.scalars.insert("pressure".into(), f.pressures.clone());
    pts.scalars.insert("speed".into(), speed);
    pts
}

/// A blue-cyan-yellow-red ramp over `t` in [0, 1].
pub fn speed_color(t: f64) -> [f64; 3] {
    let t = t.clamp(0.0, 1.0);
    let stops = [
        [0.05, 0.15, 0.6],
        [0.1, 0.7, 0.9],
        [0.95, 0.9, 0.2],
        [0.9, 0.15, 0.1],
    ];
    let s = t * 3.0;
    let k = (s.floor() as usize).min(2);
    let u = s - k as f64;
    let (a, b) = (stops[k], stops[k + 1]);
    [
        a[0] + u * (b[0] - a[0]),
        a[1] + u * (b[1] - a[1]),
        a[2] + u * (b[2] - a[2]),
    ]
}

/// Splats the particles as discs of the particle radius, orthographically onto the plane of
/// x and the up axis (looking along +y in 3-D, far particles drawn first), over the box.
pub fn splat(f: &Fluid, width: u32, vref: f64) -> Image {
    let p = &f.params;
    let up = f.up();
    let (x0, x1) = (p.box_min[0], p.box_max[0]);
    let (y0, y1) = (p.box_min[up], p.box_max[up]);
    let scale = width as f64 / (x1 - x0);
    let height = (((y1 - y0) * scale).round() as u32).clamp(1, 8192);
    let mut img = Image::new(width, height, [0.02, 0.02, 0.03, 1.0]);
    let mut order: Vec<usize> = (0..f.len()).collect();
    if p.dim == 3 {
        order.sort_by(|&a, &b| f.positions[b][1].total_cmp(&f.positions[a][1]));
    }
    let rad = (p.particle_radius * scale).max(0.75);
    for i in order {
        let cx = (f.positions[i][0] - x0) * scale;
        let cy = (y1 - f.positions[i][up]) * scale;
        let c = speed_color(dot(f.velocities[i], f.velocities[i]).sqrt() / vref);
        let px = [c[0] as f32, c[1] as f32, c[2] as f32, 1.0];
        let (lx, hx) = ((cx - rad).floor().max(0.0), (cx + rad).ceil());
        let (ly, hy) = ((cy - rad).floor().max(0.0), (cy + rad).ceil());
        let mut yy = ly;
        while yy < hy.min(height as f64) {
            let mut xx = lx;
            while xx < hx.min(width as f64) {
                let (dx, dy) = (xx + 0.5 - cx, yy + 0.5 - cy);
                if dx * dx + dy * dy <= rad * rad {
                    img.set(xx as u32, yy as u32, px);
                }
                xx += 1.0;
            }
            yy += 1.0;
        }
    }
    img
}

/// What the node keeps between frames.
#[derive(Default)]
pub struct SphState {
    key: String,
    fluid: Option<Fluid>,
    last_frame: i64,
    log: Table,
    front: Table,
    a: f64,
    n: f64,
}

impl SphState {
    fn record(&mut self, frame: i64) {
        let Some(f) = &self.fluid else { return };
        let (emax, eavg) = f.density_error();
        let front = f.front();
        self.log.push_row(&[
            frame as f64,
            f.time,
            f.steps as f64,
            f.last.iterations as f64,
            emax,
            eavg,
            f.kinetic_energy(),
            front,
            f.height(),
            f.capped_solves as f64,
        ]);
        let g = f.params.gravity.abs();
        self.front
            .push_row(&[self.n * f.time * (g / self.a).sqrt(), front / self.a]);
    }
}

impl Choice for Solver {
    const CHOICES: &'static [(&'static str, Self)] =
        &[("wcsph", Solver::Wcsph), ("dfsph", Solver::Dfsph)];
}

impl Choice for Boundary {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("particles", Boundary::Particles),
        ("walls", Boundary::Walls),
    ];
}

fn declare(b: &mut NodeBuilder) {
    b.doc("SPH fluid (WCSPH or DFSPH) in a box; advances one frame per execution.");
    b.stateful();
    let d = SphParams::default();
    b.add_input::<i64>("dimension")
        .default(d.dim as i64)
        .range(2.0, 3.0);
    b.add_choice::<Solver>("solver")
        .doc("wcsph: the course's weakly compressible SPH; dfsph: divergence-free SPH (Bender & Koschier 2017), incompressible to max_density_error.");
    b.add_choice::<Boundary>("boundary")
        .doc("particles: Akinci 2012 boundary particles sampling the box; walls: clamp with restitution only.");
    b.add_input::<[f64; 3]>("sim_box_min").default(d.box_min);
    b.add_input::<[f64; 3]>("sim_box_max").default(d.box_max);
    b.add_input::<[f64; 3]>("particle_box_min")
        .default([0.1, 0.1, 0.1])
        .doc("Initial fluid block (the fluid starts at rest).");
    b.add_input::<[f64; 3]>("particle_box_max")
        .default([0.6, 0.6, 0.6]);
    b.add_input::<[f64; 3]>("num_particle_per_axis")
        .default([0.0, 0.0, 0.0])
        .doc("Particles per axis in the block; 0 fills it with spacing 2r.");
    b.add_input::<f64>("particle_radius")
        .default(d.particle_radius)
        .range(1e-5, 10.0)
        .doc("Particle radius r; the support radius is 4r.");
    b.add_input::<f64>("rest_density")
        .default(d.rest_density)
        .range(1e-3, 1e6);
    b.add_input::<f64>("stiffness")
        .default(d.stiffness)
        .range(0.0, 1e9)
        .doc("WCSPH k in p = k((rho/rho0)^gamma - 1).");
    b.add_input::<f64>("exponent")
        .default(d.exponent)
        .range(1.0, 20.0);
    b.add_input::<f64>("viscosity")
        .default(d.viscosity)
        .range(0.0, 100.0)
        .doc("Kinematic viscosity of the course's SPH Laplacian (m^2/s).");
    b.add_input::<f64>("gravity")
        .default(d.gravity)
        .range(-1e3, 1e3)
        .doc("Along the up axis: y in 2-D, z in 3-D.");
    b.add_input::<f64>("dt")
        .default(d.dt)
        .range(1e-7, 1.0)
        .doc("Time step; the largest step when cfl > 0.");
    b.add_input::<f64>("frame_dt")
        .default(1.0 / 30.0)
        .range(1e-6, 10.0)
        .doc("Simulated time per frame.");
    b.add_input::<f64>("cfl")
        .default(d.cfl)
        .range(0.0, 2.0)
        .doc("Adaptive step dt <= cfl * 2r / v_max; 0 keeps dt fixed.");
    b.add_input::<f64>("restitution")
        .default(d.restitution)
        .range(0.0, 1.0);
    b.add_input::<i64>("max_iterations")
        .default(d.max_iterations as i64)
        .range(1.0, 100000.0)
        .doc("DFSPH: Jacobi iteration cap per solve; a solve stopped by the cap leaves compression that blows fine resolutions apart.");
    b.add_input::<f64>("max_density_error")
        .default(d.max_density_error)
        .range(1e-7, 0.5)
        .doc("DFSPH: target average compression (fraction).");
    b.add_input::<bool>("divergence")
        .default(d.divergence)
        .doc("DFSPH: run the divergence-free solver.");
    b.add_input::<i64>("image_width")
        .default(256i64)
        .range(8.0, 4096.0);
    b.add_input::<bool>("profile")
        .default(false)
        .doc("Logs the frame's wall time (Framework3D's enable time profiling).");
    b.add_input::<bool>("debug")
        .default(false)
        .doc("Logs density errors and energy each frame (Framework3D's enable debug output).");
    b.add_output::<Points>("points")
        .doc("Particles with velocity, density, pressure, speed and color.");
    b.add_output::<Vec<[f64; 3]>>("colors").doc(
        "Speed through the jet colour map, normalized to this frame's slowest and fastest particle as the course's get_vel_color_jet does.",
    );
    b.add_output::<Image>("image")
        .doc("Particles splatted on the x/up plane, coloured by speed.");
    b.add_output::<Table>("log").doc("One row per frame since the start: frame, time, steps, iterations, max_density_error, avg_density_error, kinetic_energy, front, height, capped_solves (DFSPH solves so far stopped by max_iterations unconverged).");
    b.add_output::<Table>("front").doc(
        "Front history in Martin & Moyce units: T = n t sqrt(g/a), Z = front/a, with a and n^2 a the initial block width and height.",
    );
}

/// An estimate of the bytes a simulation of `prm` takes, and the particle counts (fluid,
/// boundary) it is made of, for `ExecContext::reserve_bytes` before `Fluid::block` allocates:
/// per fluid particle 220 bytes of state and solver arrays plus 40 per neighbour (about
/// 4/3 pi (h/s)^3 in 3-D, pi (h/s)^2 in 2-D, with support h = 4r at spacing s = 2r); per
/// boundary particle 40 bytes (position, volume, grid entries). Counts follow `Fluid::block`.
fn estimated_bytes(
    prm: &SphParams,
    pmin: [f64; 3],
    pmax: [f64; 3],
    counts: Option<[usize; 3]>,
) -> (u64, f64, f64) {
    let dim = prm.dim.clamp(2, 3);
    let r = prm.particle_radius.max(1e-300);
    let mut fluid = 1.0f64;
    for a in 0..dim {
        fluid *= match counts {
            Some(c) => c[a].max(1) as f64,
            None => ((pmax[a] - pmin[a]) / (2.0 * r) + 1e-9).floor().max(1.0),
        };
    }
    let mut boundary = 0.0;
    if prm.boundary == Boundary::Particles {
        let layers = (prm.support_factor / 2.0).ceil();
        let (mut outer, mut inner) = (1.0f64, 1.0f64);
        for a in 0..dim {
            let n = ((prm.box_max[a] - prm.box_min[a]) / (2.0 * r))
                .round()
                .max(1.0);
            outer *= n + 2.0 * layers;
            inner *= n;
        }
        boundary = outer - inner;
    }
    let k = prm.support_factor / 2.0;
    let neighbours = if dim == 3 {
        4.0 / 3.0 * std::f64::consts::PI * k.powi(3)
    } else {
        std::f64::consts::PI * k * k
    };
    let bytes = fluid * (220.0 + 40.0 * neighbours) + boundary * 40.0;
    // NaN (an empty or inverted box) is left to `Fluid::block` to report.
    let bytes = if bytes.is_nan() {
        0
    } else if bytes >= u64::MAX as f64 {
        u64::MAX
    } else {
        bytes as u64
    };
    (bytes, fluid, boundary)
}

/// Simulation parameters, the fluid block corners and the optional particle counts.
type Setup = (SphParams, [f64; 3], [f64; 3], Option<[usize; 3]>);

fn read_params(ctx: &ExecContext) -> Result<Setup, NodeError> {
    let solver = ctx.choice::<Solver>("solver")?;
    let boundary = ctx.choice::<Boundary>("boundary")?;
    let dim: i64 = ctx.input("dimension")?;
    if !(2..=3).contains(&dim) {
        return Err(NodeError::invalid(
            "dimension",
            format!("{dim} is not 2 or 3"),
        ));
    }
    let prm = SphParams {
        dim: dim as usize,
        solver,
        boundary,
        box_min: ctx.input("sim_box_min")?,
        box_max: ctx.input("sim_box_max")?,
        particle_radius: ctx.input("particle_radius")?,
        support_factor: 4.0,
        rest_density: ctx.input("rest_density")?,
        stiffness: ctx.input("stiffness")?,
        exponent: ctx.input("exponent")?,
        viscosity: ctx.input("viscosity")?,
        gravity: ctx.input("gravity")?,
        dt: ctx.input("dt")?,
        cfl: ctx.input("cfl")?,
        restitution: ctx.input("restitution")?,
        max_iterations: ctx.input::<i64>("max_iterations")?.max(1) as usize,
        max_density_error: ctx.input("max_density_error")?,
        divergence: ctx.input("divergence")?,
    };
    for (name, v) in [("sim_box_min", prm.box_min), ("sim_box_max", prm.box_max)] {
        if v.iter().any(|c| !c.is_finite()) {
            return Err(NodeError::invalid(name, "must be finite"));
        }
    }
    let pmin: [f64; 3] = ctx.input("particle_box_min")?;
    let pmax: [f64; 3] = ctx.input("particle_box_max")?;
    let counts: [f64; 3] = ctx.input("num_particle_per_axis")?;
    let counts = if counts[..prm.dim].iter().all(|&c| (1.0..1e6).contains(&c)) {
        Some([
            counts[0] as usize,
            counts[1] as usize,
            counts[2].max(1.0) as usize,
        ])
    } else if counts.iter().all(|&c| c == 0.0) {
        None
    } else {
        return Err(NodeError::invalid(
            "num_particle_per_axis",
            format!("{counts:?}: give all counts (1 to 1e6) or all 0 for spacing 2r"),
        ));
    };
    Ok((prm, pmin, pmax, counts))
}

/// Checks the memory the fluid's buffers and the image will take against the budget, every
/// frame (cheap) and before a restart allocates them.
fn reserve_buffers(
    ctx: &ExecContext,
    prm: &SphParams,
    (pmin, pmax, counts): ([f64; 3], [f64; 3], Option<[usize; 3]>),
    width: u32,
) -> Result<(), NodeError> {
    let (bytes, nf, nb) = estimated_bytes(prm, pmin, pmax, counts);
    let what = format!("{nf:.3e} fluid and {nb:.3e} boundary particles");
    ctx.reserve_bytes("particle_radius", &what, bytes)?;
    // The image is as wide as asked and as high as the box's aspect (at most 8192).
    let (bx, bup) = (
        prm.box_max[0] - prm.box_min[0],
        prm.box_max[prm.dim.clamp(2, 3) - 1] - prm.box_min[prm.dim.clamp(2, 3) - 1],
    );
    let height = (bup * width as f64 / bx).round().clamp(1.0, 8192.0);
    let height = if height.is_nan() { 1 } else { height as u64 };
    let what = format!("a {width}x{height} image");
    let bytes = cgnodes_api::node::bytes_of(&[width as u64, height, 16]);
    ctx.reserve_bytes("image_width", &what, bytes)?;
    Ok(())
}

impl SphState {
    /// A fresh run: the block of fluid at rest (neighbours and densities computed), empty
    /// log and front tables, and the initial column's width `a` and height ratio `n`.
    fn start(setup: Setup, key: String, frame: i64) -> Result<SphState, NodeError> {
        let (prm, pmin, pmax, counts) = setup;
        let mut f = Fluid::block(prm, pmin, pmax, counts)
            .map_err(|e| NodeError::invalid("particle_box_min", e.to_string()))?;
        f.refresh()
            .map_err(|e| NodeError::invalid("particle_radius", e.to_string()))?;
        Ok(SphState {
            key,
            a: f.front().max(1e-12),
            n: (f.height() / f.front().max(1e-12)).sqrt(),
            fluid: Some(f),
            last_frame: frame,
            log: Table::with_columns(&[
                "frame",
                "time",
                "steps",
                "iterations",
                "max_density_error",
                "avg_density_error",
                "kinetic_energy",
                "front",
                "height",
                "capped_solves",
            ]),
            front: Table::with_columns(&["T", "Z"]),
        })
    }
}

/// The frame's log lines: time, steps and particles; a warning when DFSPH solves stopped
/// at the iteration cap; with `debug` the density errors and kinetic energy.
fn frame_report(f: &Fluid, max_iterations: usize, debug: bool) -> Vec<String> {
    let capped = f.capped_solves;
    let debug_line = debug.then(|| {
        let (emax, eavg) = f.density_error();
        format!(
            "density error max {emax:.3e} avg {eavg:.3e}, kinetic energy {:.4e}",
            f.kinetic_energy()
        )
    });
    let mut lines = vec![format!(
        "t = {:.4} s, {} steps, {} particles",
        f.time,
        f.steps,
        f.len()
    )];
    if capped > 0 {
        lines.push(format!(
            "warning: {} DFSPH solves stopped at max_iterations = {} before reaching \
             max_density_error; raise max_iterations or shorten dt",
            capped, max_iterations
        ));
    }
    lines.extend(debug_line);
    lines
}

/// Why a frame could not be simulated.
#[derive(Debug, thiserror::Error)]
enum FrameError {
    /// A step blew up or its neighbour search failed.
    #[error(transparent)]
    Advance(#[from] AdvanceError),
    /// The neighbour search at the frame's end failed.
    #[error(transparent)]
    Refresh(#[from] GridError),
}

/// Advances `f` by `frame_dt` and refreshes its neighbours and densities for the outputs.
fn advance_frame(f: &mut Fluid, frame_dt: f64, progress: &dyn Fn(f64)) -> Result<(), FrameError> {
    f.advance_progress(frame_dt, progress)?;
    f.refresh()?;
    Ok(())
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let (prm, pmin, pmax, counts) = read_params(ctx)?;
    let frame_dt: f64 = ctx.input("frame_dt")?;
    let width = ctx.input::<i64>("image_width")? as u32;
    let key = format!("{prm:?} {pmin:?} {pmax:?} {counts:?} {frame_dt}");
    let frame = ctx.frame();
    reserve_buffers(ctx, &prm, (pmin, pmax, counts), width)?;
    let started = std::time::Instant::now();
    let (profile, debug): (bool, bool) = (ctx.input("profile")?, ctx.input("debug")?);
    let progress = ctx.progress_fn();
    let st = ctx.state::<SphState>()?;
    if st.fluid.is_none() || st.key != key || frame <= st.last_frame {
        *st = SphState::start((prm.clone(), pmin, pmax, counts), key, frame)?;
        st.record(frame - 1);
    }
    let f = st.fluid.as_mut().expect("initialised above");
    if let Err(e) = advance_frame(f, frame_dt, &progress) {
        st.fluid = None;
        return Err(NodeError::unstable(format!(
            "SPH blew up in frame {frame} at {e}"
        )));
    }
    st.last_frame = frame;
    st.record(frame);
    let f = st.fluid.as_ref().expect("initialised above");
    let up = f.up();
    let vref = (2.0 * prm.gravity.abs().max(1e-3) * (prm.box_max[up] - prm.box_min[up])).sqrt();
    let pts = to_points(f, vref);
    let img = splat(f, width, vref);
    let (log, front) = (st.log.clone(), st.front.clone());
    for line in frame_report(f, prm.max_iterations, debug) {
        ctx.log(line);
    }
    if profile {
        ctx.log(format!(
            "frame took {:.1} ms",
            started.elapsed().as_secs_f64() * 1e3
        ));
    }
    let speeds = pts.scalars.get("speed").cloned().unwrap_or_default();
    ctx.set_output(
        "colors",
        cgnodes_geometry::colormap::jet_colors(&speeds, None),
    );
    ctx.set_output("points", pts);
    ctx.set_output("image", img);
    ctx.set_output("log", log);
    ctx.set_output("front", front);
    Ok(())
}

/// Registers `sph_fluid`.
pub fn register(r: &mut Registry) {
    r.add("sph_fluid", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn run(
        r: &Registry,
        params: &[(&str, Value)],
        state: &mut Option<Box<dyn std::any::Any + Send>>,
        frame: i64,
    ) -> Result<BTreeMap<String, Value>, NodeError> {
        let decl = r.get("sph_fluid").unwrap();
        let inputs: BTreeMap<String, Value> = params
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect();
        let files = FileEnv::default();
        let mut ctx = ExecContext::standalone(decl, inputs, state, &files, frame);
        (decl.exec.as_ref().unwrap())(&mut ctx)?;
        Ok(ctx.take_outputs())
    }

    fn small() -> Vec<(&'static str, Value)> {
        vec![
            ("dimension", Value::Int(2)),
            ("sim_box_max", Value::Vec3([1.0, 1.0, 0.0])),
            ("particle_box_max", Value::Vec3([0.3, 0.3, 0.0])),
            ("particle_radius", Value::Float(0.02)),
            ("stiffness", Value::Float(2e4)),
        ]
    }

    #[test]
    fn frames_advance_and_parameters_reset_the_state() {
        let mut r = Registry::new();
        register(&mut r);
        let mut st = None;
        run(&r, &small(), &mut st, 0).unwrap();
        let out = run(&r, &small(), &mut st, 1).unwrap();
        let Some(Value::Table(log)) = out.get("log") else {
            panic!("no log")
        };
        let t = log.column("time").unwrap();
        assert_eq!(t.len(), 3);
        assert!((t[2] - 2.0 / 30.0).abs() < 1e-9);
        let Some(Value::Points(p)) = out.get("points") else {
            panic!("no points")
        };
        // 0.2 / 0.04 = 5 particles per axis (spacing 2r in the block [0.1, 0.3]^2).
        assert_eq!(p.dim, 2);
        assert_eq!(p.positions.len(), 25);
        assert!(p.scalars.contains_key("density"));
        // Free fall for 2/30 s lowers the mean height 0.2 by g t^2 / 2 = 0.022 (no floor yet).
        let mean_y = p.positions.iter().map(|x| x[1]).sum::<f64>() / 25.0;
        assert!((mean_y - (0.2 - 0.5 * 9.8 * (2.0f64 / 30.0).powi(2))).abs() < 2e-3);
        let Some(Value::Image(img)) = out.get("image") else {
            panic!("no image")
        };
        assert_eq!((img.width, img.height), (256, 256));
        // A changed parameter restarts the simulation.
        let mut changed = small();
        changed.push(("viscosity", Value::Float(0.01)));
        let out = run(&r, &changed, &mut st, 2).unwrap();
        let Some(Value::Table(log)) = out.get("log") else {
            panic!("no log")
        };
        assert_eq!(log.column("time").unwrap().len(), 2);
    }

    #[test]
    fn blow_up_is_reported_with_frame_and_step() {
        let mut r = Registry::new();
        register(&mut r);
        let mut st = None;
        let mut p = small();
        p.extend([
            ("cfl", Value::Float(0.0)),
            ("dt", Value::Float(0.05)),
            ("stiffness", Value::Float(1e7)),
            ("frame_dt", Value::Float(1.0)),
        ]);
        let e = run(&r, &p, &mut st, 0).unwrap_err();
        assert_eq!(e.kind, ErrorKind::Unstable);
        assert!(
            e.message.contains("frame 0") && e.message.contains("step"),
            "{}",
            e.message
        );
    }

    #[test]
    fn bad_boxes_are_rejected() {
        let mut r = Registry::new();
        register(&mut r);
        let mut st = None;
        let mut p = small();
        p.push(("particle_box_max", Value::Vec3([2.0, 0.3, 0.0])));
        let e = run(&r, &p, &mut st, 0).unwrap_err();
        assert_eq!(e.kind, ErrorKind::InvalidInput);
        // A huge 3-D box with tiny particles would need billions of wall particles.
        let p = vec![
            ("sim_box_max", Value::Vec3([100.0; 3])),
            ("particle_radius", Value::Float(0.01)),
        ];
        let e = run(&r, &p, &mut st, 0).unwrap_err();
        assert_eq!(e.kind, ErrorKind::InvalidInput);
        assert!(e.message.contains("boundary particles"), "{}", e.message);
    }
}
