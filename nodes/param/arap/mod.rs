//! ARAP, ASAP and hybrid parameterization (Liu et al. 2008), fast and fold-free.
//!
//! - `local_global`: `arap_parameterize`, the local/global iteration for ARAP and the hybrid
//!   model; its local step over all triangles, log rows and result are in `energy`, the loop
//!   in `solver`, its global step
//!   in `system`, the fold-free line search in `line_search` and `fold_free`, its settings
//!   and constants in `options`.
//! - `arap`: nodes `arap` and `arap_hybrid`, and how `ArapError` becomes a `NodeError`.
//! - `asap`: `asap_parameterize`, one linear solve; node `asap`.
//! - `frames`: per-triangle isometric frames, Jacobians and closed-form 2x2 decompositions.
//! - `injective`: the largest orientation-preserving step (Smith & Schaefer 2015) and flips.
//! - `error`: `ArapError`, why the algorithms refused their input.
//!
//! Method, costs and measurements: `docs/arap.md`.

// the node `arap` lives in `arap.rs`, named after the node type like every node file
#[allow(clippy::module_inception)]
pub mod arap;
pub mod asap;
pub mod energy;
pub mod error;
mod fold_free;
pub mod frames;
pub mod injective;
mod line_search;
pub mod local_global;
pub mod options;
pub mod prepared;
mod solver;
mod system;

pub use asap::{asap_parameterize, AsapResult};
pub use energy::{ArapIteration, ArapResult, LOG_COLUMNS};
pub use error::ArapError;
pub use local_global::{arap_parameterize, arap_parameterize_prepared, arap_parameterize_progress};
pub use options::{ArapOptions, RefactorSchedule, LOCAL_RINGS};
pub use prepared::ArapSystem;

use super::tutte::{tutte_parameterize, BoundaryShape, TutteWeights};
use cgnodes_api::prelude::*;

/// Why an iterative parameterization stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// The relative energy decrease fell below the tolerance.
    Tolerance,
    /// The iteration limit was reached.
    Iterations,
    /// No step along the global solution lowered the energy without flipping a triangle.
    NoProgress,
}

impl StopReason {
    /// `tolerance`, `iterations` or `no_progress`.
    pub fn as_str(self) -> &'static str {
        match self {
            StopReason::Tolerance => "tolerance",
            StopReason::Iterations => "iterations",
            StopReason::NoProgress => "no_progress",
        }
    }
}

/// The connected component of each vertex through triangles (`u32::MAX` for vertices in no
/// triangle), and the number of components.
pub fn component_of(n: usize, triangles: &[[u32; 3]]) -> (Vec<u32>, usize) {
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    let mut used = vec![false; n];
    for t in triangles {
        for k in 0..3 {
            used[t[k] as usize] = true;
            let (a, b) = (find(&mut parent, t[k]), find(&mut parent, t[(k + 1) % 3]));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut label = vec![u32::MAX; n];
    let mut comp = vec![u32::MAX; n];
    let mut count = 0u32;
    for v in 0..n {
        if used[v] {
            let r = find(&mut parent, v as u32) as usize;
            if label[r] == u32::MAX {
                label[r] = count;
                count += 1;
            }
            comp[v] = label[r];
        }
    }
    (comp, count as usize)
}

/// The starting UVs of the `arap` nodes: the `init` mesh's per-vertex UVs (or its positions
/// when it is a flat mesh without UVs), else Tutte's embedding on a circle with mean-value
/// weights and holes filled, which has no folds (Floater 2003). Returns a note for the log.
pub fn init_uvs(mesh: &Mesh, init: Option<&Mesh>) -> Result<(Vec<[f64; 2]>, String), NodeError> {
    let n = mesh.num_vertices();
    match init {
        Some(m) => {
            if m.num_vertices() != n {
                return Err(NodeError::invalid(
                    "init",
                    format!(
                        "init mesh has {} vertices but the mesh has {n}",
                        m.num_vertices()
                    ),
                ));
            }
            if let Some(uv) = m.vertex_uvs() {
                return Ok((uv, "initial UVs from the init mesh".into()));
            }
            if m.uvs.is_some() {
                return Err(NodeError::invalid(
                    "init",
                    "init UVs differ between the corners of a vertex (seams); ARAP needs one UV per vertex",
                ));
            }
            if m.positions.iter().all(|p| p[2] == 0.0) {
                return Ok((
                    m.positions.iter().map(|p| [p[0], p[1]]).collect(),
                    "initial UVs from the flat init mesh's positions".into(),
                ));
            }
            Err(NodeError::invalid(
                "init",
                "init mesh has no UVs and is not flat (z = 0)",
            ))
        }
        None => default_init(mesh),
    }
}

/// Initial UVs given as a list (the `init_uv` socket): one finite UV per vertex of a mesh
/// with `n` vertices.
pub fn init_uv_list(n: usize, uv: Vec<[f64; 2]>) -> Result<(Vec<[f64; 2]>, String), NodeError> {
    if uv.len() != n {
        return Err(NodeError::invalid(
            "init_uv",
            format!("{} UVs for {n} vertices (one per vertex)", uv.len()),
        ));
    }
    if uv.iter().flatten().any(|x| !x.is_finite()) {
        return Err(NodeError::invalid("init_uv", "UVs must be finite"));
    }
    Ok((uv, "initial UVs from the init_uv list".into()))
}

fn default_init(mesh: &Mesh) -> Result<(Vec<[f64; 2]>, String), NodeError> {
    let uv = tutte_parameterize(mesh, TutteWeights::MeanValue, BoundaryShape::Circle, true)?;
    let holes = mesh.topology().boundary_loops.len().saturating_sub(1);
    Ok((
        uv,
        format!("initial UVs: Tutte, mean-value weights, circle boundary, {holes} hole(s) filled"),
    ))
}

/// The node outputs: `mesh` (the input with per-vertex UVs, normalized into `[0,1]²` when
/// asked) and `flat` (the triangulated mesh laid at `(u, v, 0)` at the solved size, same UVs).
pub fn uv_outputs(mesh: &Mesh, tri_mesh: &Mesh, uv: &[[f64; 2]], normalize: bool) -> (Mesh, Mesh) {
    let tex = if normalize {
        normalized(uv)
    } else {
        uv.to_vec()
    };
    let mut out = mesh.clone();
    out.uvs = Some(Attribute {
        domain: Domain::Vertex,
        values: tex.clone(),
    });
    let mut flat = tri_mesh.clone();
    flat.positions = uv.iter().map(|p| [p[0], p[1], 0.0]).collect();
    flat.normals = None;
    flat.uvs = Some(Attribute {
        domain: Domain::Vertex,
        values: tex,
    });
    (out, flat)
}

/// `uv` moved and uniformly scaled so that its bounding box fits `[0,1]²` at the origin.
pub fn normalized(uv: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in uv {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let ext = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    if !(ext > 0.0 && ext.is_finite()) {
        return uv.to_vec();
    }
    uv.iter()
        .map(|p| [(p[0] - lo[0]) / ext, (p[1] - lo[1]) / ext])
        .collect()
}

/// Registers `arap`, `arap_hybrid` and `asap`.
pub fn register(r: &mut Registry) {
    arap::register(r);
    asap::register(r);
}
