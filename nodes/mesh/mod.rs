//! Mesh nodes: loading, saving, inspecting and triangulating meshes, and primitive meshes
//! (`mesh_plane`, `mesh_grid`).

pub mod buffer;
pub mod compose;
pub mod info;
pub mod load;
pub mod mesh_grid;
pub mod mesh_plane;
pub mod obj;
pub mod off;
pub mod ply;
pub mod save;
pub mod triangulate;
pub mod usda;
pub mod vertex_select;

use crate::registry::Registry;

/// Registers the mesh nodes.
pub fn register(r: &mut Registry) {
    r.with_category("mesh", |r| {
        load::register(r);
        save::register(r);
        info::register(r);
        triangulate::register(r);
        compose::register(r);
        buffer::register(r);
        mesh_plane::register(r);
        mesh_grid::register(r);
    });
}
