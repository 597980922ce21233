//! Mesh nodes: loading, saving, inspecting and triangulating meshes, and primitive meshes
//! (`mesh_plane`, `mesh_grid`).

crate::node_domain! {
    category: "mesh",
    nodes: [buffer, mesh_compose, mesh_grid, mesh_info, mesh_load, mesh_plane, mesh_save, mesh_transform, mesh_triangulate, points_to_mesh, set_vert_color],
    modules: [obj, off, ply, usda, vertex_select],
}
