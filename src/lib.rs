//! cgnodes: a node-graph batch executor for computer graphics.
//!
//! A graph is a JSON file of typed nodes and links (`graph`); it is checked against the
//! node registry (`validate`), planned over the nodes the requested outputs need, and run
//! in parallel with caching (`exec`). Built-in nodes live in `nodes`, one file per node or
//! small family; each node's algorithm is a plain function callable without the runtime.
//!
//! Modules depend only on earlier ones, in this order: `io`, `types`, `node`, `registry`,
//! `plugin` (adds external nodes to a registry), `graph::format`, `f3d` (imports Framework3D
//! trees against a registry), `graph::load` and `graph::overrides`, `validate`, `cache`,
//! `exec`, `chart`, `shard`, `sweep`, `sweep_merge`, `report`, `cli`. The built-in nodes (`nodes`) use only `io`, `types`,
//! `node` and `registry`; `nodes::builtin_registry()` assembles them.

pub mod cache;
pub mod chart;
pub mod cli;
pub mod exec;
pub mod f3d;
pub mod fuzz;
pub mod graph;
pub mod io;
pub mod node;
pub mod plugin;
pub mod registry;
pub mod report;
pub mod shard;
pub mod sweep;
pub mod sweep_merge;
pub mod types;
pub mod validate;

#[path = "../nodes/mod.rs"]
pub mod nodes;

/// Everything a node file needs.
pub mod prelude {
    pub use crate::node::{
        Choice, ErrorKind, ExecContext, FileEnv, NodeBuilder, NodeDecl, NodeError,
    };
    pub use crate::registry::Registry;
    pub use crate::types::*;
    pub use std::sync::Arc;
}
