//! Graphs: the file format (`format`), what the command line changes in a loaded graph
//! (`overrides`: `--set`, `--frames`), and loading files (`load`), which may import a
//! Framework3D node tree against a registry. See `docs/graph-format.md`.
//!
//! Dependency order inside: `format` comes before the `f3d` module (the importer builds a
//! `GraphFile`), which comes before `load`.

pub mod format;
pub mod load;
pub mod overrides;
pub mod typed_schema;

pub use format::{
    migrate, schema, split_link, Graph, GraphFile, LinkSpec, NodeSpec, FORMAT, VERSION,
};
pub use load::{load, load_with, parse, parse_with, LoadError};
pub use overrides::{apply_sets, parse_frames, SetError};
pub use typed_schema::typed_schema;
