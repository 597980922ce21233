//! Render nodes: the scene description shared by the rasterizer and the tracers (camera,
//! lights, materials, scene) and the rasterizer.

pub mod camera;
pub mod light;
pub mod material;
pub mod mesh_uv_project;
pub mod raster;
pub mod scene;

use crate::registry::Registry;

/// Registers the render nodes.
pub fn register(r: &mut Registry) {
    r.with_category("render", |r| {
        camera::register(r);
        light::register(r);
        material::register(r);
        scene::register(r);
        raster::register(r);
        mesh_uv_project::register(r);
    });
}

/// Runs the render node `name` standalone on `inputs` and returns its outputs (for the
/// unit tests of the node files).
#[cfg(test)]
pub(crate) fn run_node(
    name: &str,
    inputs: std::collections::BTreeMap<String, crate::types::Value>,
) -> Result<std::collections::BTreeMap<String, crate::types::Value>, crate::node::NodeError> {
    let mut r = Registry::new();
    register(&mut r);
    let decl = r.get(name).unwrap();
    let mut state = None;
    let files = crate::node::FileEnv::default();
    let mut ctx = crate::node::ExecContext::standalone(decl, inputs, &mut state, &files, 0);
    (decl.exec.as_ref().unwrap())(&mut ctx)?;
    Ok(ctx.take_outputs())
}
