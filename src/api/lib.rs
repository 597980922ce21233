//! cgnodes-api: what a node needs and nothing more. Value types (`types`), node
//! declarations and execution (`node`), the registry nodes are added to (`registry`), file
//! helpers (`io`) and a seeded random generator (`rng`). Built-in node families and
//! third-party plugin crates depend on this crate alone; it knows no node and no runtime.

pub mod io;
pub mod node;
pub mod registry;
pub mod rng;
pub mod types;

/// Everything a node file needs.
pub mod prelude {
    pub use crate::node::{
        Choice, ErrorKind, ExecContext, FileEnv, NodeBuilder, NodeDecl, NodeError,
    };
    pub use crate::registry::Registry;
    pub use crate::types::*;
    pub use std::sync::Arc;
}
