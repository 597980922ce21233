//! Render nodes: the scene description shared by the rasterizer and the tracers (camera,
//! lights, materials, scene), image input and output, and the rasterizer.

pub mod camera;
pub mod image_io;
pub mod light;
pub mod material;
/// Moved to `nodes::mesh::mesh_plane`; kept under the old path for its importers.
pub use crate::nodes::mesh::mesh_plane as primitive;
pub mod raster;
pub mod scene;
pub mod uv_project;

use crate::registry::Registry;

/// Registers the render nodes.
pub fn register(r: &mut Registry) {
    camera::register(r);
    light::register(r);
    material::register(r);
    scene::register(r);
    image_io::register(r);
    raster::register(r);
    uv_project::register(r);
}
