//! Mesh nodes: loading, saving, inspecting and triangulating meshes, and primitive meshes
//! (`mesh_plane`, `mesh_grid`).

pub mod buffer;
pub mod mesh_compose;
pub mod mesh_grid;
pub mod mesh_info;
pub mod mesh_load;
pub mod mesh_plane;
pub mod mesh_save;
pub mod mesh_triangulate;
pub mod obj;
pub mod off;
pub mod ply;
pub mod usda;
pub mod vertex_select;

use crate::registry::Registry;

/// Registers the mesh nodes.
pub fn register(r: &mut Registry) {
    r.with_category("mesh", |r| {
        mesh_load::register(r);
        mesh_save::register(r);
        mesh_info::register(r);
        mesh_triangulate::register(r);
        mesh_compose::register(r);
        buffer::register(r);
        mesh_plane::register(r);
        mesh_grid::register(r);
    });
}
