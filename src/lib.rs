//! cgnodes: a node-graph batch executor for computer graphics.
//!
//! This crate is the facade users build and run (as Bevy's `bevy` is over its crates): the
//! command line (`cli`), and a registry of the built-in node families that its cargo features
//! turn on (`nodes::builtin_registry`). The layers live in their own crates and are
//! re-exported here under their usual paths:
//! - `cgnodes_api` (`types`, `node`, `registry`, `io`, `rng`, `prelude`): what a node needs;
//!   plugin crates depend on it alone.
//! - `cgnodes_runtime` (`graph`, `validate`, `cache`, `exec`, `plugin`, `f3d`, `report`,
//!   `chart`, `shard`, `sweep`, `sweep_merge`): the runtime, which knows no node.
//! - one crate per node family (`nodes::mesh`, `nodes::param`, ...), each on the API alone
//!   plus the shared crates `cgnodes_formats`, `cgnodes_geometry`, `cgnodes_linalg`,
//!   `cgnodes_nn`.

pub mod cli;
pub mod fuzz;
pub mod nodes;

pub use cgnodes_api::{io, node, prelude, registry, rng, types};
pub use cgnodes_runtime::{
    cache, chart, exec, f3d, graph, plugin, report, shard, sweep, sweep_merge, validate,
};
