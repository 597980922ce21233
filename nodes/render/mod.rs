//! Render nodes: the scene description shared by the rasterizer and the tracers (camera,
//! lights, materials, scene) and the rasterizer. (`image_io` re-exports the image file
//! functions that moved to the image domain.)

pub mod camera;
pub mod image_io;
pub mod light;
pub mod material;
pub mod primitive;
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
    primitive::register(r);
    raster::register(r);
    uv_project::register(r);
}
