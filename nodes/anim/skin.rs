//! `skin`: a skinned mesh at a USD time code, by linear blend skinning (`lbs.rs`) or
//! dual-quaternion skinning (`dqs.rs`), through the mesh's own UsdSkel binding, optionally
//! posed by another skeleton with the same joints.

use super::dqs::dqs;
use super::lbs::{
    check_influences, joint_matrices, lbs_normals, lbs_points, normalize_weights, Influences,
    SkinError,
};
use super::pose::skinning_transforms;
use cgnodes_api::prelude::*;
use cgnodes_formats::usda::skel::from_rows;

/// The skinning method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SkinMethod {
    /// Linear blend skinning.
    Lbs,
    /// Dual-quaternion skinning (Kavan et al. 2007).
    Dqs,
}

impl Choice for SkinMethod {
    const CHOICES: &'static [(&'static str, Self)] =
        &[("lbs", SkinMethod::Lbs), ("dqs", SkinMethod::Dqs)];
}

/// A skinned mesh and what the caller should be warned about.
#[derive(Clone, Debug)]
pub struct Skinned {
    /// The mesh with moved points (and normals); faces and other attributes as before.
    pub mesh: Mesh,
    /// Warnings (weights normalized, non-rigid joints under DQS, face normals dropped).
    pub warnings: Vec<String>,
}

/// The skeleton that poses the mesh (`skeleton`, else the bound one) and the socket its
/// errors name; `Err` when its joint count differs from the bound skeleton's.
fn posing_skeleton<'a>(
    bind: &'a SkinBinding,
    skeleton: Option<&'a Skeleton>,
) -> Result<(&'a Skeleton, &'static str), NodeError> {
    let (skel, socket) = match skeleton {
        Some(s) => (s, "skeleton"),
        None => (&*bind.skeleton, "mesh"),
    };
    if skel.joints.len() != bind.skeleton.joints.len() {
        return Err(NodeError::invalid(
            "skeleton",
            format!(
                "Skeleton '{}' has {} joints but Mesh '{}' is bound to '{}' with {}",
                skel.prim,
                skel.joints.len(),
                bind.prim,
                bind.skeleton.prim,
                bind.skeleton.joints.len()
            ),
        ));
    }
    Ok((skel, socket))
}

/// The binding's joint weights normalized to sum 1 per vertex, with a warning when any did
/// not (`Err`: a vertex whose weights add up to zero).
fn normalized_weights(
    bind: &SkinBinding,
    nv: usize,
    warnings: &mut Vec<String>,
) -> Result<Vec<f64>, SkinError> {
    let (weights, changed) = normalize_weights(bind.influences, &bind.joint_weights)?;
    if changed > 0 {
        warnings.push(format!(
            "warning: the joint weights of {changed} of {nv} vertices of '{}' did not add up to 1 and were normalized",
            bind.prim
        ));
    }
    Ok(weights)
}

/// `Err` naming the first skinned vertex that is not finite.
fn check_finite(out: &Mesh, socket: &str) -> Result<(), NodeError> {
    match out
        .positions
        .iter()
        .position(|p| p.iter().any(|x| !x.is_finite()))
    {
        Some(i) => Err(NodeError::invalid(
            socket,
            format!("the skinned vertex {i} is not finite"),
        )),
        None => Ok(()),
    }
}

/// Skins `mesh` (which must carry a `SkinBinding`) at `time` with `method`, posed by
/// `skeleton` when given (it must have as many joints as the bound one), else by the bound
/// skeleton. Errors name the socket at fault (`mesh` or `skeleton`) and the prim.
pub fn skin_mesh(
    mesh: &Mesh,
    skeleton: Option<&Skeleton>,
    time: f64,
    method: SkinMethod,
) -> Result<Skinned, NodeError> {
    let bind = mesh.skin.as_deref().ok_or_else(|| {
        NodeError::invalid(
            "mesh",
            "the mesh has no skeleton binding (load a UsdSkel-bound .usda mesh with mesh_load)",
        )
    })?;
    let mesh_err = |e: String| NodeError::invalid("mesh", format!("Mesh '{}': {e}", bind.prim));
    if !time.is_finite() {
        return Err(NodeError::invalid(
            "time",
            format!("time {time} is not finite"),
        ));
    }
    let (skel, socket) = posing_skeleton(bind, skeleton)?;
    let nv = mesh.num_vertices();
    let inf = Influences {
        count: bind.influences,
        indices: &bind.joint_indices,
        weights: &bind.joint_weights,
    };
    check_influences(&inf, nv, skel.joints.len()).map_err(|e| mesh_err(e.to_string()))?;
    let mut warnings = Vec::new();
    let weights =
        normalized_weights(bind, nv, &mut warnings).map_err(|e| mesh_err(e.to_string()))?;
    let inf = Influences {
        weights: &weights,
        ..inf
    };
    let xf =
        skinning_transforms(skel, time).map_err(|e| NodeError::invalid(socket, e.to_string()))?;
    let g = from_rows(&bind.geom_bind);
    let w = from_rows(&bind.skel_to_world);
    let mut out = mesh.clone();
    // Normals: per vertex or per corner (a corner takes its vertex's influences).
    let corner_vertex: Vec<u32>;
    let normals = match &mesh.normals {
        Some(a) if a.domain == Domain::Vertex => Some((&a.values[..], None)),
        Some(a) if a.domain == Domain::Corner => {
            corner_vertex = mesh.face_indices().to_vec();
            Some((&a.values[..], Some(&corner_vertex[..])))
        }
        Some(_) => {
            warnings.push("warning: per-face normals cannot be skinned and were dropped".into());
            out.normals = None;
            None
        }
        None => None,
    };
    match method {
        SkinMethod::Lbs => {
            let m = joint_matrices(&g, &xf, &w);
            out.positions = lbs_points(&mesh.positions, &inf, &m);
            if let (Some((ns, map)), Some(a)) = (normals, out.normals.as_mut()) {
                a.values = lbs_normals(ns, map, &inf, &m)
                    .map_err(|e| NodeError::invalid(socket, e.to_string()))?;
            }
        }
        SkinMethod::Dqs => {
            let (p, n, off) = dqs(&mesh.positions, normals, &inf, &g, &xf, &w);
            out.positions = p;
            if let (Some(n), Some(a)) = (n, out.normals.as_mut()) {
                a.values = n;
            }
            if off > 1e-6 {
                warnings.push(format!(
                    "warning: a joint transform of '{}' scales or shears ({off:.3e} from a rotation); DQS keeps only its rotation",
                    skel.prim
                ));
            }
        }
    }
    check_finite(&out, socket)?;
    Ok(Skinned {
        mesh: out,
        warnings,
    })
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Skins a UsdSkel-bound mesh at a time code by linear blend or dual-quaternion skinning.");
    b.add_input::<Mesh>("mesh")
        .doc("A mesh with a skeleton binding (mesh_load of a UsdSkel .usda).");
    b.add_input::<Skeleton>("skeleton").optional().doc(
        "Poses the mesh instead of its bound skeleton (same joints); unlinked: the bound one.",
    );
    b.add_input::<f64>("time")
        .default(0.0)
        .doc("USD time code; outside the animation's samples the ends are held.");
    b.add_choice::<SkinMethod>("method").doc(
        "lbs: linear blend skinning; dqs: dual-quaternion skinning (keeps volume under twist).",
    );
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let skel: Option<Arc<Skeleton>> = ctx.input_opt("skeleton")?;
    let time: f64 = ctx.input("time")?;
    let method = ctx.choice::<SkinMethod>("method")?;
    let s = skin_mesh(&mesh, skel.as_deref(), time, method)?;
    for w in s.warnings {
        ctx.log(w);
    }
    ctx.set_output("mesh", s.mesh);
    Ok(())
}

/// Registers `skin`.
pub fn register(r: &mut Registry) {
    r.add("skin", declare, execute);
}
