//! Parameterization nodes: boundary mapping, minimal surfaces, Tutte's embedding with three
//! weightings, texture mapping, UV layout rendering and distortion metrics.

crate::node_domain! {
    category: "param",
    nodes: [arap, boundary_map, minimal_surface, render_uv, texture_map, tutte, uv_metrics],
    modules: [laplacian, laplacian_rows, triangles],
}
