//! Ray and path tracing: a BVH (PLOC clustering) with watertight intersection, sampling
//! routines, BSDFs, an environment light, an OBJ + MTL scene loader, a Whitted ray tracer
//! and a path tracer.

crate::node_domain! {
    category: "trace",
    nodes: [render_path, render_whitted, scene_load],
    modules: [bsdf, bvh, camera_grid, direct, environment, lane_math, path_film, path_lanes, render_scene, sampling, tracer_node, v3],
}
