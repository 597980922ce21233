//! Ray and path tracing: a BVH (PLOC clustering) with watertight intersection, sampling
//! routines, BSDFs, an environment light, an OBJ + MTL scene loader, a Whitted ray tracer
//! and a path tracer.

pub mod bsdf;
pub mod bvh;
pub mod camera;
pub mod camera_grid;
pub mod camera_sample;
pub mod direct;
mod lane_avx;
pub mod lane_math;
pub mod path_film;
pub mod path_lanes;
pub mod path_one;
pub mod render_path;
pub mod render_scene;
pub mod render_whitted;
pub mod sampling;
pub mod scene_load;
pub mod trace_error;
pub mod tracer_node;
pub use cgnodes_geometry::environment;
pub use cgnodes_geometry::v3;

use cgnodes_api::registry::Registry;

/// Registers this family's nodes, in the `trace` category.
pub fn register(r: &mut Registry) {
    r.with_category("trace", |r| {
        render_path::register(r);
        render_whitted::register(r);
        scene_load::register(r);
    });
}
