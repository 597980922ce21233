//! The USD stage of a Framework3D project (issue 32): what the composition graph builds and
//! the render graph reads. `model` holds the stage (meshes, point clouds, UsdLux lights, a
//! camera), `write` writes it as one USDA layer, `read` reads such a layer (or any USDA file
//! with those prims) back, and `scene` turns a stage into cgnodes' `Scene` and `Camera`
//! (particles as small octahedra, the dome light's image loaded, a default framing when the
//! stage has no camera). The nodes: `stage_load` (the render graph's `render_scene_*`),
//! `stage_light`, `stage_read` and `stage_merge` (the composition graph's `comp_*`), whose
//! `layer` outputs are USDA text.

pub mod model;
pub mod read;
pub mod scene;
pub mod stage_load;
pub mod stage_nodes;
pub mod write;

#[cfg(test)]
mod tests;

pub use model::{LightKind, Stage, StageCamera, StageLight, StageMesh, StagePoints, UpAxis};
pub use read::read_stage;
pub use scene::{default_camera, stage_to_scene};
pub use write::write_stage;

/// Registers `stage_load`, `stage_light`, `stage_read` and `stage_merge`.
pub fn register(r: &mut cgnodes_api::registry::Registry) {
    stage_load::register(r);
    stage_nodes::register(r);
}
