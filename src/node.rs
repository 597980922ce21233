//! The node API: how a node declares its sockets and how it runs.
//!
//! A node is two plain functions and a name, in the shape Framework3D and Blender use:
//!
//! ```
//! use cgnodes::prelude::*;
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

use crate::types::{FromValue, SocketType, Typed, Value};
use serde::{Deserialize, Serialize};
use std::any::Any;
use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The function that runs a node.
pub type ExecFn = Arc<dyn Fn(&mut ExecContext) -> Result<(), NodeError> + Send + Sync>;

/// What a file-path socket is for, so the runtime can resolve and guard it.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum FileRole {
    /// Not a path.
    #[default]
    None,
    /// A file the node reads (resolved against the graph's folder; its stamp enters the cache key).
    Input,
    /// A file the node writes (resolved under the output directory).
    Output,
}

/// One socket of a node declaration.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
pub struct SocketDecl {
    /// Socket name (snake_case).
    pub name: String,
    /// Socket type.
    #[serde(rename = "type")]
    pub ty: SocketType,
    /// One-line description.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub doc: String,
    /// Default literal used when the graph gives neither a literal nor a link.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub default: Option<serde_json::Value>,
    /// Smallest accepted number (Int and Float sockets).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<f64>,
    /// Largest accepted number (Int and Float sockets).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<f64>,
    /// Accepted strings (enum parameters).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub choices: Option<Vec<String>>,
    /// Whether the input may be left unconnected with no default.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub optional: bool,
    /// Whether the socket names a file to read or write.
    #[serde(default, skip_serializing_if = "is_none_role")]
    pub file: FileRole,
}

fn is_none_role(r: &FileRole) -> bool {
    *r == FileRole::None
}

impl SocketDecl {
    /// Checks a literal against range and choices; `Err` says what is wrong.
    pub fn check_literal(&self, v: &Value) -> Result<(), String> {
        let num = match v {
            Value::Int(i) => Some(*i as f64),
            Value::Float(f) => Some(*f),
            _ => None,
        };
        if let Some(x) = num {
            if let Some(lo) = self.min {
                if x < lo {
                    return Err(format!("{x} is below the minimum {lo}"));
                }
            }
            if let Some(hi) = self.max {
                if x > hi {
                    return Err(format!("{x} is above the maximum {hi}"));
                }
            }
        }
        if let (Some(choices), Value::String(s)) = (&self.choices, v) {
            if !choices.iter().any(|c| c == s) {
                return Err(format!("'{s}' is not one of {}", choices.join(", ")));
            }
        }
        Ok(())
    }

    /// The default as a value of the socket's type.
    pub fn default_value(&self) -> Option<Value> {
        self.default
            .as_ref()
            .and_then(|j| Value::from_json(&self.ty, j).ok())
    }
}

/// The declaration of a node type: sockets, documentation and how it behaves over time.
#[derive(Clone, Serialize, Deserialize, schemars::JsonSchema)]
pub struct NodeDecl {
    /// Node type name (snake_case).
    #[serde(rename = "type")]
    pub type_name: String,
    /// One-line description.
    #[serde(default)]
    pub doc: String,
    /// Domain the node belongs to (for listings).
    #[serde(default)]
    pub category: String,
    /// Input sockets (literals in `params` or links in `inputs`).
    #[serde(default)]
    pub inputs: Vec<SocketDecl>,
    /// Output sockets.
    #[serde(default)]
    pub outputs: Vec<SocketDecl>,
    /// Keeps state between frames (simulations); runs every frame.
    #[serde(default)]
    pub stateful: bool,
    /// Depends on the frame number even without state.
    #[serde(default)]
    pub time_dependent: bool,
    /// Writes files or prints: evaluated by default, never skipped as unused.
    #[serde(default)]
    pub sink: bool,
    /// Where the node comes from: `builtin`, a crate name, or a plugin folder.
    #[serde(default)]
    pub source: String,
    /// The function that runs the node.
    #[serde(skip)]
    #[schemars(skip)]
    pub exec: Option<ExecFn>,
}

impl std::fmt::Debug for NodeDecl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NodeDecl")
            .field("type", &self.type_name)
            .finish_non_exhaustive()
    }
}

impl NodeDecl {
    /// The input socket called `name`.
    pub fn input(&self, name: &str) -> Option<&SocketDecl> {
        self.inputs.iter().find(|s| s.name == name)
    }

    /// The output socket called `name`.
    pub fn output(&self, name: &str) -> Option<&SocketDecl> {
        self.outputs.iter().find(|s| s.name == name)
    }
}

/// Builds a `NodeDecl` (`b.add_input::<Mesh>("mesh")`).
pub struct NodeBuilder {
    decl: NodeDecl,
}

/// Sets the details of one socket; returned by `add_input` and `add_output`.
pub struct SocketBuilder<'a> {
    s: &'a mut SocketDecl,
}

impl<'a> SocketBuilder<'a> {
    /// The value used when the graph gives none.
    pub fn default(self, v: impl Into<Value>) -> Self {
        self.s.default = v.into().to_json();
        self
    }
    /// The accepted range, inclusive.
    pub fn range(self, min: f64, max: f64) -> Self {
        self.s.min = Some(min);
        self.s.max = Some(max);
        self
    }
    /// The smallest accepted value.
    pub fn min(self, min: f64) -> Self {
        self.s.min = Some(min);
        self
    }
    /// The largest accepted value.
    pub fn max(self, max: f64) -> Self {
        self.s.max = Some(max);
        self
    }
    /// The accepted strings; the first is the default unless one is set.
    pub fn choices(self, c: &[&str]) -> Self {
        self.s.choices = Some(c.iter().map(|x| x.to_string()).collect());
        if self.s.default.is_none() {
            self.s.default = c.first().map(|x| serde_json::json!(x));
        }
        self
    }
    /// One-line description.
    pub fn doc(self, d: &str) -> Self {
        self.s.doc = d.to_string();
        self
    }
    /// May be left unconnected; the node then sees `None` from `input_opt`.
    pub fn optional(self) -> Self {
        self.s.optional = true;
        self
    }
    /// The string names a file to read.
    pub fn file_in(self) -> Self {
        self.s.file = FileRole::Input;
        self
    }
    /// The string names a file to write under the output directory.
    pub fn file_out(self) -> Self {
        self.s.file = FileRole::Output;
        self
    }
}

impl NodeBuilder {
    /// A builder for node type `type_name`.
    pub fn new(type_name: &str) -> NodeBuilder {
        NodeBuilder {
            decl: NodeDecl {
                type_name: type_name.to_string(),
                doc: String::new(),
                category: String::new(),
                inputs: Vec::new(),
                outputs: Vec::new(),
                stateful: false,
                time_dependent: false,
                sink: false,
                source: "builtin".into(),
                exec: None,
            },
        }
    }
    /// One-line description of the node.
    pub fn doc(&mut self, d: &str) -> &mut Self {
        self.decl.doc = d.to_string();
        self
    }
    /// Domain the node belongs to.
    pub fn category(&mut self, c: &str) -> &mut Self {
        self.decl.category = c.to_string();
        self
    }
    /// Adds an input socket of type `T`.
    pub fn add_input<T: Typed>(&mut self, name: &str) -> SocketBuilder<'_> {
        self.add_input_of(name, T::socket_type())
    }
    /// Adds an input socket of a type known only at run time (plugins).
    pub fn add_input_of(&mut self, name: &str, ty: SocketType) -> SocketBuilder<'_> {
        self.decl.inputs.push(socket(name, ty));
        SocketBuilder {
            s: self.decl.inputs.last_mut().expect("just pushed"),
        }
    }
    /// Adds an output socket of type `T`.
    pub fn add_output<T: Typed>(&mut self, name: &str) -> SocketBuilder<'_> {
        self.add_output_of(name, T::socket_type())
    }
    /// Adds an output socket of a type known only at run time.
    pub fn add_output_of(&mut self, name: &str, ty: SocketType) -> SocketBuilder<'_> {
        self.decl.outputs.push(socket(name, ty));
        SocketBuilder {
            s: self.decl.outputs.last_mut().expect("just pushed"),
        }
    }
    /// Keeps state between frames and runs every frame.
    pub fn stateful(&mut self) -> &mut Self {
        self.decl.stateful = true;
        self.decl.time_dependent = true;
        self
    }
    /// Reads the frame number.
    pub fn time_dependent(&mut self) -> &mut Self {
        self.decl.time_dependent = true;
        self
    }
    /// Has an effect outside the graph (writes a file, prints): evaluated by default.
    pub fn sink(&mut self) -> &mut Self {
        self.decl.sink = true;
        self
    }
    /// Where the node comes from (default `builtin`).
    pub fn source(&mut self, s: &str) -> &mut Self {
        self.decl.source = s.to_string();
        self
    }
    /// The finished declaration.
    pub fn build(mut self, exec: ExecFn) -> NodeDecl {
        self.decl.exec = Some(exec);
        self.decl
    }
}

fn socket(name: &str, ty: SocketType) -> SocketDecl {
    SocketDecl {
        name: name.to_string(),
        ty,
        doc: String::new(),
        default: None,
        min: None,
        max: None,
        choices: None,
        optional: false,
        file: FileRole::None,
    }
}

/// What kind of failure a node reports; `cgnodes sweep` records it per run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorKind {
    /// An input value the node cannot use (out of range, wrong shape, NaN).
    InvalidInput,
    /// The mesh has the wrong topology (not a disk, not manifold, closed).
    Topology,
    /// A simulation blew up (NaN, infinity, energy growth).
    Unstable,
    /// A parameterization or deformation folded triangles.
    Folded,
    /// A linear system was singular or not positive definite.
    Singular,
    /// Reading or writing a file failed.
    Io,
    /// The node is not supported in this configuration.
    Unsupported,
    /// An external plugin failed or timed out.
    Plugin,
    /// A bug in cgnodes: please report it.
    Internal,
}

impl std::fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = serde_json::to_value(self).unwrap_or_default();
        write!(f, "{}", s.as_str().unwrap_or("error"))
    }
}

/// A node's failure: its kind, the socket at fault (if any) and a message.
#[derive(Clone, Debug, thiserror::Error)]
#[error("{}{message}", socket.as_ref().map(|s| format!("socket '{s}': ")).unwrap_or_default())]
pub struct NodeError {
    /// What kind of failure.
    pub kind: ErrorKind,
    /// The socket at fault.
    pub socket: Option<String>,
    /// What went wrong, for a person.
    pub message: String,
}

impl NodeError {
    /// A failure of `kind`.
    pub fn new(kind: ErrorKind, message: impl Into<String>) -> NodeError {
        NodeError {
            kind,
            socket: None,
            message: message.into(),
        }
    }
    /// A bad value on input `socket`.
    pub fn invalid(socket: &str, message: impl Into<String>) -> NodeError {
        NodeError {
            kind: ErrorKind::InvalidInput,
            socket: Some(socket.to_string()),
            message: message.into(),
        }
    }
    /// A mesh with the wrong topology on input `socket`.
    pub fn topology(socket: &str, message: impl Into<String>) -> NodeError {
        NodeError {
            kind: ErrorKind::Topology,
            socket: Some(socket.to_string()),
            message: message.into(),
        }
    }
    /// A simulation that blew up.
    pub fn unstable(message: impl Into<String>) -> NodeError {
        NodeError::new(ErrorKind::Unstable, message)
    }
    /// A singular or indefinite system.
    pub fn singular(message: impl Into<String>) -> NodeError {
        NodeError::new(ErrorKind::Singular, message)
    }
    /// A file that could not be read or written.
    pub fn io(path: &Path, err: impl std::fmt::Display) -> NodeError {
        NodeError::new(ErrorKind::Io, format!("{}: {err}", path.display()))
    }
    /// Sets the socket at fault.
    pub fn at(mut self, socket: &str) -> NodeError {
        self.socket = Some(socket.to_string());
        self
    }
}

/// Where a run reads and writes files.
#[derive(Clone, Debug)]
pub struct FileEnv {
    /// Folder of the graph file: relative input paths resolve here.
    pub graph_dir: PathBuf,
    /// Further folders searched for input files (`--assets`).
    pub asset_dirs: Vec<PathBuf>,
    /// Output directory: writer nodes write under it.
    pub out_dir: PathBuf,
    /// Lets writers use absolute paths and `..` (off by default).
    pub allow_write_anywhere: bool,
}

impl Default for FileEnv {
    fn default() -> Self {
        FileEnv {
            graph_dir: ".".into(),
            asset_dirs: Vec::new(),
            out_dir: "out".into(),
            allow_write_anywhere: false,
        }
    }
}

impl FileEnv {
    /// Resolves an input path: absolute as is, else against the graph's folder, then the
    /// asset folders; the first that exists wins (the graph's folder when none does).
    pub fn input_path(&self, p: &str) -> PathBuf {
        let path = Path::new(p);
        if path.is_absolute() {
            return path.to_path_buf();
        }
        let first = self.graph_dir.join(path);
        if first.exists() {
            return first;
        }
        for d in &self.asset_dirs {
            let c = d.join(path);
            if c.exists() {
                return c;
            }
        }
        first
    }

    /// Resolves an output path under the output directory, substituting `{frame}` and
    /// `{frame:04}`; refuses absolute paths and `..` unless writes anywhere are allowed.
    pub fn output_path(&self, p: &str, frame: i64) -> Result<PathBuf, String> {
        let p = substitute_frame(p, frame)?;
        let path = Path::new(&p);
        if !self.allow_write_anywhere {
            if path.is_absolute() {
                return Err(format!(
                    "'{p}' is absolute; outputs go under the output directory (use --allow-write-anywhere to permit this)"
                ));
            }
            if path.components().any(|c| {
                !matches!(
                    c,
                    std::path::Component::Normal(_) | std::path::Component::CurDir
                )
            }) {
                return Err(format!(
                    "'{p}' leaves the output directory; outputs go under it (use --allow-write-anywhere to permit this)"
                ));
            }
        }
        if p.is_empty() {
            return Err("empty output path".into());
        }
        Ok(if path.is_absolute() {
            path.to_path_buf()
        } else {
            self.out_dir.join(path)
        })
    }
}

/// Replaces `{frame}` and `{frame:0N}` in a path.
pub fn substitute_frame(p: &str, frame: i64) -> Result<String, String> {
    let mut out = String::new();
    let mut rest = p;
    while let Some(i) = rest.find("{frame") {
        out.push_str(&rest[..i]);
        let tail = &rest[i..];
        let end = tail
            .find('}')
            .ok_or_else(|| format!("unclosed '{{' in '{p}'"))?;
        let spec = &tail[6..end];
        if spec.is_empty() {
            out.push_str(&frame.to_string());
        } else if let Some(w) = spec.strip_prefix(":0").or_else(|| spec.strip_prefix(':')) {
            let w: usize = w
                .parse()
                .map_err(|_| format!("bad frame format '{{frame{spec}}}' in '{p}'"))?;
            out.push_str(&format!("{frame:0w$}"));
        } else {
            return Err(format!("bad frame format '{{frame{spec}}}' in '{p}'"));
        }
        rest = &tail[end + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

/// Reports a node's progress (fraction in 0..=1).
pub type ProgressFn = Arc<dyn Fn(&str, f64) + Send + Sync>;

/// Everything a node sees while it runs: its inputs, its outputs, the frame, its state
/// between frames, and the file environment.
pub struct ExecContext<'a> {
    /// The node's id in the graph.
    pub node_id: &'a str,
    /// The node's declaration.
    pub decl: &'a NodeDecl,
    pub(crate) inputs: BTreeMap<String, Value>,
    pub(crate) outputs: BTreeMap<String, Value>,
    pub(crate) frame: i64,
    pub(crate) state: &'a mut Option<Box<dyn Any + Send>>,
    pub(crate) files: &'a FileEnv,
    pub(crate) logs: Vec<String>,
    pub(crate) written: Vec<PathBuf>,
    pub(crate) progress: Option<ProgressFn>,
    /// The outputs someone will read; `None` = all of them.
    pub(crate) wanted: Option<BTreeSet<String>>,
}

impl<'a> ExecContext<'a> {
    /// A context for running a node directly, outside a graph (tests, Rust users).
    pub fn standalone(
        decl: &'a NodeDecl,
        inputs: BTreeMap<String, Value>,
        state: &'a mut Option<Box<dyn Any + Send>>,
        files: &'a FileEnv,
        frame: i64,
    ) -> ExecContext<'a> {
        let mut all = BTreeMap::new();
        for s in &decl.inputs {
            if let Some(v) = inputs.get(&s.name).cloned().or_else(|| s.default_value()) {
                all.insert(s.name.clone(), v.convert_to(&s.ty).unwrap_or(v));
            }
        }
        ExecContext {
            node_id: "standalone",
            decl,
            inputs: all,
            outputs: BTreeMap::new(),
            frame,
            state,
            files,
            logs: Vec::new(),
            written: Vec::new(),
            progress: None,
            wanted: None,
        }
    }

    /// Limits the outputs this context reports as wanted to `names` (standalone use; by
    /// default every output is wanted).
    pub fn want_only(&mut self, names: &[&str]) {
        self.wanted = Some(names.iter().map(|n| n.to_string()).collect());
    }

    /// Whether anyone will read output `name`: it is linked to a node that runs, the user
    /// asked for it (the node is a target, or `RunOptions::read_outputs` names it), or the
    /// caller wants every output. A node may skip computing an output that is not wanted
    /// (and not set it); nodes that never ask compute everything, which is always correct.
    /// The cache records skipped outputs, so a later run that wants one reruns the node.
    pub fn output_wanted(&self, name: &str) -> bool {
        match &self.wanted {
            None => true,
            Some(w) => w.contains(name),
        }
    }

    /// Reads input `name` as `T`. Fails when the input is unset or of another type.
    pub fn input<T: FromValue>(&self, name: &str) -> Result<T, NodeError> {
        self.input_opt(name)?
            .ok_or_else(|| NodeError::invalid(name, "no value given"))
    }

    /// Reads an optional input: `None` when unconnected with no default.
    pub fn input_opt<T: FromValue>(&self, name: &str) -> Result<Option<T>, NodeError> {
        match self.inputs.get(name) {
            None => Ok(None),
            Some(v) => T::from_value(v).map(Some).ok_or_else(|| {
                NodeError::new(
                    ErrorKind::Internal,
                    format!(
                        "input '{name}' holds a {} which the node cannot read",
                        v.socket_type()
                    ),
                )
                .at(name)
            }),
        }
    }

    /// The raw value on input `name`.
    pub fn input_value(&self, name: &str) -> Option<&Value> {
        self.inputs.get(name)
    }

    /// Sets output `name`.
    pub fn set_output(&mut self, name: &str, v: impl Into<Value>) {
        self.outputs.insert(name.to_string(), v.into());
    }

    /// The outputs set so far.
    pub fn outputs(&self) -> &BTreeMap<String, Value> {
        &self.outputs
    }

    /// Takes the outputs (for standalone use).
    pub fn take_outputs(&mut self) -> BTreeMap<String, Value> {
        std::mem::take(&mut self.outputs)
    }

    /// The current frame (0 when the graph is not run over frames).
    pub fn frame(&self) -> i64 {
        self.frame
    }

    /// This node's state between frames, created with `Default` on first use.
    /// Returns an error if the stored state has another type.
    pub fn state<T: Default + Send + 'static>(&mut self) -> Result<&mut T, NodeError> {
        if self.state.as_ref().is_some_and(|s| !s.is::<T>()) || self.state.is_none() {
            *self.state = Some(Box::new(T::default()));
        }
        self.state
            .as_mut()
            .and_then(|s| s.downcast_mut::<T>())
            .ok_or_else(|| NodeError::new(ErrorKind::Internal, "state has another type"))
    }

    /// Drops this node's state (a simulation restarts on its next frame).
    pub fn reset_state(&mut self) {
        *self.state = None;
    }

    /// Resolves an input file path against the graph's folder and the asset folders.
    pub fn input_path(&self, p: &str) -> PathBuf {
        self.files.input_path(p)
    }

    /// Resolves an output path under the output directory (with `{frame}` substituted);
    /// `socket` names the socket the path came from, for the error.
    pub fn output_path(&self, socket: &str, p: &str) -> Result<PathBuf, NodeError> {
        self.files
            .output_path(p, self.frame)
            .map_err(|e| NodeError::invalid(socket, e))
    }

    /// Writes a file atomically (temporary file in the same folder, then rename).
    pub fn write_file(&mut self, path: &Path, bytes: &[u8]) -> Result<(), NodeError> {
        self.write_with(path, |w| w.write_all(bytes))
    }

    /// Writes a file atomically through a writer; on error nothing is left behind.
    pub fn write_with(
        &mut self,
        path: &Path,
        f: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    ) -> Result<(), NodeError> {
        crate::io::write_atomic(path, f).map_err(|e| NodeError::io(path, e))?;
        self.written.push(path.to_path_buf());
        Ok(())
    }

    /// Records a file written by other means (already atomically), so the cache knows it.
    pub fn record_written(&mut self, path: &Path) {
        self.written.push(path.to_path_buf());
    }

    /// The files written so far.
    pub fn written(&self) -> &[PathBuf] {
        &self.written
    }

    /// Adds a line to the run log.
    pub fn log(&mut self, msg: impl Into<String>) {
        self.logs.push(msg.into());
    }

    /// The log lines so far.
    pub fn logs(&self) -> &[String] {
        &self.logs
    }

    /// Reports progress, 0 to 1.
    pub fn progress(&self, fraction: f64) {
        if let Some(p) = &self.progress {
            p(self.node_id, fraction.clamp(0.0, 1.0));
        }
    }

    /// The file environment.
    pub fn files(&self) -> &FileEnv {
        self.files
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_patterns() {
        assert_eq!(substitute_frame("a_{frame}.obj", 7).unwrap(), "a_7.obj");
        assert_eq!(
            substitute_frame("a_{frame:04}.obj", 7).unwrap(),
            "a_0007.obj"
        );
        assert!(substitute_frame("a_{frame:x}.obj", 7).is_err());
    }

    #[test]
    fn output_paths_stay_inside() {
        let env = FileEnv::default();
        assert!(env.output_path("../x.obj", 0).is_err());
        assert!(env.output_path("/tmp/x.obj", 0).is_err());
        assert!(env.output_path("a/../../x.obj", 0).is_err());
        assert_eq!(
            env.output_path("sub/x.obj", 0).unwrap(),
            Path::new("out/sub/x.obj")
        );
        let any = FileEnv {
            allow_write_anywhere: true,
            ..FileEnv::default()
        };
        assert!(any.output_path("/tmp/x.obj", 0).is_ok());
    }
}
