//! cgnodes-runtime: everything between a graph file and its outputs, with no node of its own.
//!
//! A graph is a JSON file of typed nodes and links (`graph`); it is checked against a node
//! registry (`validate`), planned over the nodes the requested outputs need, and run in
//! parallel with caching (`exec`). Modules depend only on earlier ones, in this order:
//! `plugin` (adds external nodes to a registry), `graph::format`, `f3d` (imports Framework3D
//! trees against a registry), `graph::load` and `graph::overrides`, `validate`, `cache`,
//! `exec`, `chart`, `shard`, `sweep`, `sweep_merge`, `report`. What the runtime needs from
//! node families (reading and previewing meshes in the report) comes through the registry
//! (`cgnodes_api::registry::MeshHooks`).

pub mod cache;
pub mod chart;
pub mod exec;
pub mod f3d;
pub mod graph;
pub mod plugin;
pub mod report;
pub mod shard;
pub mod sweep;
pub mod sweep_merge;
pub mod validate;

/// The node families the runtime's unit tests run graphs with (the runtime itself has none).
#[cfg(test)]
pub(crate) fn test_registry() -> cgnodes_api::registry::Registry {
    let mut r = cgnodes_api::registry::Registry::new();
    cgnodes_basic::register(&mut r);
    cgnodes_mesh::register(&mut r);
    cgnodes_param::register(&mut r);
    r
}
