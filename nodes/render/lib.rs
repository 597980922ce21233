//! Render nodes: the scene description shared by the rasterizer and the tracers (camera,
//! lights, materials, scene), the rasterizer, and mesh previews and their animations
//! (`mesh_preview`, `mesh_sequence`), and the G-buffer passes over its output (`gbuffer`).

pub mod camera;
pub mod gbuffer;
pub mod light;
pub mod material;
pub mod mesh_preview;
pub mod mesh_sequence;
pub mod mesh_uv_project;
pub mod raster;
pub mod scene;
pub mod stage;

use cgnodes_api::registry::Registry;

/// An error from another crate (the camera check, scene flattening, mesh transforms, image
/// decoding, linear solves), boxed with its own message so this family's typed errors can
/// carry it whatever its type.
pub type BoxedError = Box<dyn std::error::Error + Send + Sync>;

/// Registers this family's nodes, in the `render` category.
pub fn register(r: &mut Registry) {
    r.with_category("render", |r| {
        camera::register(r);
        gbuffer::register(r);
        light::register(r);
        material::register(r);
        mesh_sequence::register(r);
        mesh_uv_project::register(r);
        raster::register(r);
        scene::register(r);
        stage::register(r);
    });
}

/// Runs the render node `name` standalone on `inputs` and returns its outputs (for the
/// unit tests of the node files).
#[cfg(test)]
pub(crate) fn run_node(
    name: &str,
    inputs: std::collections::BTreeMap<String, cgnodes_api::types::Value>,
) -> Result<
    std::collections::BTreeMap<String, cgnodes_api::types::Value>,
    cgnodes_api::node::NodeError,
> {
    let mut r = cgnodes_api::registry::Registry::new();
    register(&mut r);
    let decl = r.get(name).unwrap();
    decl.check_inputs(&inputs)?;
    let mut state = None;
    let files = cgnodes_api::node::FileEnv::default();
    let mut ctx = cgnodes_api::node::ExecContext::standalone(decl, inputs, &mut state, &files, 0);
    (decl.exec.as_ref().unwrap())(&mut ctx)?;
    Ok(ctx.take_outputs())
}
