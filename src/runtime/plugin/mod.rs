//! External-process plugins: nodes written in Python or any other language.
//!
//! A plugin is a folder holding a manifest, `cgnodes-plugin.json`, that names the plugin,
//! the protocol version it speaks, the command that runs it, and its nodes, declared with
//! the same schema `cgnodes nodes --json` prints. Each declared node is registered like a
//! built-in one; running it starts the command in the plugin's folder, sends a JSON request
//! on stdin (node type, frame, inputs; arrays as `.npy` files in a per-call temporary
//! folder) and reads a JSON response on stdout. Everything the plugin writes to stderr is
//! its log. A non-zero exit, a response that is not JSON or does not fit the declared
//! outputs, or a timeout becomes a node error of kind `plugin` with the tail of stderr; the
//! rest of the graph goes on. The protocol is specified in `docs/plugins.md`.
//!
//! Plugins are found only through `--plugins DIR`, the `CGNODES_PLUGIN_PATH` variable and
//! the user's config folder (`$XDG_CONFIG_HOME/cgnodes/plugins`, else
//! `~/.config/cgnodes/plugins`), never through a graph: a graph is data and cannot make
//! cgnodes run a program.

mod call;
pub mod codec;
mod host;
mod manifest;
pub mod npy;
mod process;

pub use call::{call, CallResult, CallStats, Runner};
pub use host::{
    cli_registry, discover, load_all, register, search_path, user_dir, Origin, PluginPathError,
};
pub use manifest::{load, DeclProblem, Manifest, ManifestError, ManifestProblem, Plugin};

/// The protocol version this build speaks.
pub const PROTOCOL: u32 = 1;
/// The manifest's file name.
pub const MANIFEST: &str = "cgnodes-plugin.json";
/// Seconds a plugin call may take when the manifest sets no `timeout`.
pub const DEFAULT_TIMEOUT_S: f64 = 60.0;
/// The environment variable listing plugin folders (separated like `PATH`).
pub const PATH_VAR: &str = "CGNODES_PLUGIN_PATH";
/// The input socket added to every plugin node (unless the manifest declares it) that
/// limits the call's duration in seconds.
pub const TIMEOUT_SOCKET: &str = "timeout";
