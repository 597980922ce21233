//! The built-in node families this build includes (one cargo feature each, all on by
//! default), and the registry of their nodes.

#[cfg(feature = "anim")]
pub use cgnodes_anim as anim;
#[cfg(feature = "basic")]
pub use cgnodes_basic as basic;
#[cfg(feature = "curve")]
pub use cgnodes_curve as curve;
#[cfg(feature = "image")]
pub use cgnodes_image as image;
#[cfg(feature = "learn")]
pub use cgnodes_learn as learn;
#[cfg(feature = "mesh")]
pub use cgnodes_mesh as mesh;
#[cfg(feature = "metrics")]
pub use cgnodes_metrics as metrics;
#[cfg(feature = "param")]
pub use cgnodes_param as param;
#[cfg(feature = "render")]
pub use cgnodes_render as render;
#[cfg(feature = "sim")]
pub use cgnodes_sim as sim;
#[cfg(feature = "trace")]
pub use cgnodes_trace as trace;

pub use cgnodes_formats as formats;

use cgnodes_api::registry::{MeshHooks, Registry};

/// A registry with every built-in node of this build (what `cgnodes` runs with before plugins
/// are added), and the mesh services the run report uses.
pub fn builtin_registry() -> Registry {
    let mut r = Registry::new();
    register_all(&mut r);
    r
}

/// Registers every built-in node of this build, and the report's mesh hooks.
pub fn register_all(r: &mut Registry) {
    #[cfg(feature = "anim")]
    anim::register(r);
    #[cfg(feature = "basic")]
    basic::register(r);
    #[cfg(feature = "curve")]
    curve::register(r);
    #[cfg(feature = "image")]
    image::register(r);
    #[cfg(feature = "learn")]
    learn::register(r);
    #[cfg(feature = "mesh")]
    mesh::register(r);
    #[cfg(feature = "metrics")]
    metrics::register(r);
    #[cfg(feature = "param")]
    param::register(r);
    #[cfg(feature = "render")]
    render::register(r);
    #[cfg(feature = "trace")]
    trace::register(r);
    #[cfg(feature = "sim")]
    sim::register(r);
    r.mesh_hooks = mesh_hooks();
}

/// Mesh previews, drawn by the render family when this build has it.
fn mesh_hooks() -> MeshHooks {
    MeshHooks {
        #[cfg(feature = "render")]
        preview: Some(render::mesh_preview::preview_framed_on),
        #[cfg(not(feature = "render"))]
        preview: None,
    }
}
