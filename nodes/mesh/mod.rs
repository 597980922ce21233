//! Mesh nodes: loading, saving, inspecting and triangulating meshes.

pub mod load;
pub mod save;

use crate::registry::Registry;

/// Registers the mesh nodes.
pub fn register(r: &mut Registry) {
    load::register(r);
    save::register(r);
}
