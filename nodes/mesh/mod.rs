//! Mesh nodes: loading, saving, inspecting and triangulating meshes, and primitive meshes
//! (`mesh_plane`, `mesh_grid`).

crate::node_domain! {
    category: "mesh",
    nodes: [buffer, create_grid, gaussian_curvature, mesh_compose, mesh_grid, mesh_info, mesh_load, mesh_plane, mesh_save, mesh_transform, mesh_triangulate, points_to_mesh, random_uv_points, set_vert_color, signed_color_map],
    modules: [obj, off, ply, usda, vertex_select],
}
