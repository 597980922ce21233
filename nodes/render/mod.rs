//! Render nodes: the scene description shared by the rasterizer and the tracers (camera,
//! lights, materials, scene), the rasterizer, and mesh previews and their animations
//! (`mesh_preview`, `mesh_sequence`), and the G-buffer passes over its output (`gbuffer`).

crate::node_domain! {
    category: "render",
    nodes: [camera, gbuffer, light, material, mesh_sequence, mesh_uv_project, raster, scene, stage],
    modules: [mesh_preview],
}

/// Runs the render node `name` standalone on `inputs` and returns its outputs (for the
/// unit tests of the node files).
#[cfg(test)]
pub(crate) fn run_node(
    name: &str,
    inputs: std::collections::BTreeMap<String, crate::types::Value>,
) -> Result<std::collections::BTreeMap<String, crate::types::Value>, crate::node::NodeError> {
    let mut r = crate::registry::Registry::new();
    register(&mut r);
    let decl = r.get(name).unwrap();
    let mut state = None;
    let files = crate::node::FileEnv::default();
    let mut ctx = crate::node::ExecContext::standalone(decl, inputs, &mut state, &files, 0);
    (decl.exec.as_ref().unwrap())(&mut ctx)?;
    Ok(ctx.take_outputs())
}
