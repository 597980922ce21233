//! The node API: how a node declares its sockets and how it runs.
//!
//! A node is two plain functions and a name, in the shape Framework3D and Blender use:
//!
//! ```
//! use cgnodes_api::prelude::*;
//!
//! fn declare(b: &mut NodeBuilder) {
//!     b.doc("Scales a number.");
//!     b.add_input::<f64>("x").default(1.0);
//!     b.add_input::<f64>("factor").default(2.0).range(0.0, 100.0);
//!     b.add_output::<f64>("value");
//! }
//!
//! fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
//!     let x: f64 = ctx.input("x")?;
//!     let k: f64 = ctx.input("factor")?;
//!     ctx.set_output("value", x * k);
//!     Ok(())
//! }
//!
//! let mut registry = Registry::new();
//! registry.add("scale", declare, execute);
//! ```

mod builder;
mod choice;
mod context;
mod decl;
mod error;
mod files;
mod memory;
mod provenance;

pub use builder::{NodeBuilder, SocketBuilder};
pub use choice::{parse_choice, Choice};
pub use context::{ExecContext, Finished, LogFn, LogLevel, ProgressFn, RunSetup, PROGRESS_UNKNOWN};
pub use decl::{CompanionFn, ExecFn, FileRole, NodeDecl, SocketDecl};
pub use error::{ErrorKind, NodeError};
pub use files::{substitute_frame, FileEnv};
pub use memory::{
    bytes_of, default_memory_limit, format_size, parse_size, physical_memory,
    FALLBACK_MEMORY_LIMIT, MAX_MEMORY_ENV,
};
pub use provenance::{Provenance, ProvenanceError};
