//! Mesh nodes: loading, saving, inspecting and triangulating meshes, and primitive meshes
//! (`mesh_plane`, `mesh_grid`).

pub mod buffer;
pub mod create_grid;
pub mod gaussian_curvature;
pub mod mesh_compose;
pub mod mesh_grid;
pub mod mesh_info;
pub mod mesh_load;
pub mod mesh_plane;
pub mod mesh_save;
pub mod mesh_transform;
pub mod mesh_triangulate;
pub mod points_to_mesh;
pub mod random_uv_points;
pub mod set_vert_color;
pub mod signed_color_map;
pub use cgnodes_formats::{obj, off, ply, usda};
pub use cgnodes_geometry::vertex_select;

use cgnodes_api::registry::Registry;

/// Registers this family's nodes, in the `mesh` category.
pub fn register(r: &mut Registry) {
    r.with_category("mesh", |r| {
        buffer::register(r);
        create_grid::register(r);
        gaussian_curvature::register(r);
        mesh_compose::register(r);
        mesh_grid::register(r);
        mesh_info::register(r);
        mesh_load::register(r);
        mesh_plane::register(r);
        mesh_save::register(r);
        mesh_transform::register(r);
        mesh_triangulate::register(r);
        points_to_mesh::register(r);
        random_uv_points::register(r);
        set_vert_color::register(r);
        signed_color_map::register(r);
    });
}
