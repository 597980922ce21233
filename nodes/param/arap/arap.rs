//! Nodes `arap` and `arap_hybrid`: thin wrappers of `arap_parameterize` (ARAP, or the hybrid
//! model with a `lambda` socket) that read the sockets, start from `init_uvs`, and write the
//! UV'd mesh, the flat mesh and the convergence log. Also how the ARAP family's errors
//! (`ArapError`) are reported as `NodeError`s, with the socket at fault.

use super::error::ArapError;
use super::local_global::arap_parameterize_prepared;
use super::options::ArapOptions;
use super::prepared::ArapSystem;
use super::{init_uv_list, init_uvs, uv_outputs};
use cgnodes_api::prelude::*;

impl From<ArapError> for NodeError {
    fn from(e: ArapError) -> NodeError {
        let message = e.to_string();
        match e {
            ArapError::InitLength { .. } | ArapError::InitNotFinite(_) => {
                NodeError::invalid("init", message)
            }
            ArapError::NoTriangles
            | ArapError::VertexOutOfRange(_)
            | ArapError::DegenerateTriangle { .. } => NodeError::invalid("mesh", message),
            ArapError::Tolerance => NodeError::invalid("tolerance", message),
            ArapError::Lambda => NodeError::invalid("lambda", message),
            ArapError::Pin { .. } | ArapError::SystemOptions => NodeError::invalid("pin", message),
            ArapError::Pins => NodeError::invalid("pins", message),
            ArapError::Components(_) => NodeError::topology("mesh", message),
            ArapError::FoldedStart(_) => NodeError::new(ErrorKind::Folded, message),
            ArapError::SingularLaplacian(_) | ArapError::SingularAsap(_) => {
                NodeError::singular(message)
            }
        }
    }
}

fn declare_common(b: &mut NodeBuilder) {
    b.add_input::<Mesh>("mesh")
        .doc("Mesh to flatten (triangulated if needed).");
    b.add_input::<Mesh>("init").optional().doc(
        "Mesh carrying the initial UVs (per vertex). Default: Tutte on a circle with mean-value weights, holes filled.",
    );
    b.add_input::<Vec<[f64; 2]>>("init_uv").optional().doc(
        "Or the initial UVs as a list, one per vertex (a Framework3D Float2Buffer such as a student's InitialTexCoords); not together with init.",
    );
    let d = ArapOptions::default();
    b.add_input::<i64>("iterations")
        .default(d.iterations as i64)
        .range(0.0, 100000.0)
        .doc("Maximum number of local/global iterations.");
    b.add_input::<f64>("tolerance")
        .default(d.tolerance)
        .range(0.0, 1.0)
        .doc("Stop when an iteration lowers the energy by less than this fraction.");
    b.add_input::<bool>("injective")
        .default(d.injective)
        .doc("Fold-free: never accept a step that flips a triangle.");
    b.add_input::<i64>("pin")
        .default(-1i64)
        .min(-1.0)
        .doc("Vertex kept at its initial UV; -1: the first vertex.");
    b.add_input::<bool>("normalize").default(true).doc(
        "Scale and move the UVs into [0,1]² (same scale on both axes); `flat` keeps the true size.",
    );
    b.add_output::<Mesh>("mesh")
        .doc("The input mesh with per-vertex UVs.");
    b.add_output::<Mesh>("flat")
        .doc("The flattened mesh (UV, 0), at the 3-D scale.");
    b.add_output::<Table>("log").doc(
        "Per iteration: energy, flips, elapsed_ms, step, blocked (1: cut short to avoid a flip), refactors (numeric refactorizations after stiffening triangles); meta: stop_reason, flips, energy, reweighted, refactors.",
    );
}

fn declare_arap(b: &mut NodeBuilder) {
    b.doc("ARAP parameterization (Liu et al. 2008 local/global), fold-free by default.");
    declare_common(b);
}

fn declare_hybrid(b: &mut NodeBuilder) {
    b.doc("Hybrid ARAP/ASAP parameterization (Liu et al. 2008 §4.3): lambda blends similarity (0) and rotation (large).");
    declare_common(b);
    b.add_input::<f64>("lambda")
        .default(1.0)
        .range(0.0, 1e9)
        .doc("Weight of the scale term: 0 is ASAP, large values tend to ARAP.");
}

fn execute_with(ctx: &mut ExecContext, lambda: Option<f64>) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let init: Option<Arc<Mesh>> = ctx.input_opt("init")?;
    let iterations: i64 = ctx.input("iterations")?;
    let tolerance: f64 = ctx.input("tolerance")?;
    let injective: bool = ctx.input("injective")?;
    let pin: i64 = ctx.input("pin")?;
    let normalize: bool = ctx.input("normalize")?;
    let tri_mesh = mesh.triangulated();
    let triangles = tri_mesh
        .triangles()
        .ok_or_else(|| NodeError::invalid("mesh", "could not triangulate the mesh"))?;
    let init_uv: Option<Vec<[f64; 2]>> = ctx.input_opt("init_uv")?;
    if init_uv.is_some() && init.is_some() {
        return Err(NodeError::invalid(
            "init_uv",
            "link either init (a mesh with UVs) or init_uv (a UV list), not both",
        ));
    }
    let opts = ArapOptions {
        iterations: iterations.max(0) as usize,
        tolerance,
        injective,
        pin: (pin >= 0).then_some(pin as usize),
        lambda,
        ..Default::default()
    };
    // the start (Tutte's by default) on one core, the Laplacian's factorization on the other
    let (start, system) = rayon::join(
        || match init_uv {
            Some(uv) => init_uv_list(tri_mesh.num_vertices(), uv),
            None => init_uvs(&tri_mesh, init.as_deref()),
        },
        || ArapSystem::new(&tri_mesh.positions, &triangles, &opts),
    );
    let (uv0, init_note) = start?;
    ctx.log(init_note);
    let res = arap_parameterize_prepared(system?, &uv0, &opts, &ctx.progress_fn())?;
    let mut table = Table::with_columns(&super::LOG_COLUMNS);
    for r in &res.log {
        table.push_row(&[
            r.iteration as f64,
            r.energy,
            r.flips as f64,
            r.elapsed_ms,
            r.step,
            f64::from(u8::from(r.blocked)),
            r.refactors as f64,
        ]);
    }
    table
        .meta
        .insert("stop_reason".into(), res.stop_reason.as_str().into());
    table.meta.insert("flips".into(), res.flips.to_string());
    table
        .meta
        .insert("reweighted".into(), res.reweighted.to_string());
    table
        .meta
        .insert("refactors".into(), res.refactors.to_string());
    if !res.stop_detail.is_empty() {
        table
            .meta
            .insert("stop_detail".into(), res.stop_detail.clone());
        ctx.log(format!("stopped: {}", res.stop_detail));
    }
    table
        .meta
        .insert("energy".into(), format!("{:.6e}", res.energy));
    ctx.log(format!(
        "{} iterations, energy {:.4e} -> {:.4e}, {} flipped triangles, stopped: {}",
        res.log.len() - 1,
        res.log[0].energy,
        res.energy,
        res.flips,
        res.stop_reason.as_str()
    ));
    let (out, flat) = uv_outputs(&mesh, &tri_mesh, &res.uv, normalize);
    ctx.set_output("mesh", out);
    ctx.set_output("flat", flat);
    ctx.set_output("log", table);
    Ok(())
}

fn execute_arap(ctx: &mut ExecContext) -> Result<(), NodeError> {
    execute_with(ctx, None)
}

fn execute_hybrid(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let lambda: f64 = ctx.input("lambda")?;
    execute_with(ctx, Some(lambda))
}

/// Registers `arap` and `arap_hybrid`.
pub fn register(r: &mut Registry) {
    r.add("arap", declare_arap, execute_arap);
    r.add("arap_hybrid", declare_hybrid, execute_hybrid);
}
