//! Ray and path tracing: a binned-SAH BVH with watertight intersection, sampling
//! routines, BSDFs, an OBJ + MTL scene loader, a Whitted ray tracer and a path tracer.

pub mod bsdf;
pub mod bvh;
pub mod render_path;
pub mod render_scene;
pub mod render_whitted;
pub mod sampling;
pub mod scene_load;
pub mod tracer_node;
pub mod v3;

use crate::registry::Registry;

/// Registers the trace nodes.
pub fn register(r: &mut Registry) {
    r.with_category("trace", |r| {
        render_path::register(r);
        scene_load::register(r);
        render_whitted::register(r);
    });
}
