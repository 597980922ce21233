//! `ExecContext`: everything a node sees while it runs (inputs, outputs, frame, state
//! between frames, file environment, log and progress).

use super::{ErrorKind, FileEnv, NodeDecl, NodeError, Provenance};
use crate::types::{FromValue, Value};
use std::any::Any;
use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Reports a node's progress (fraction in 0..=1).
pub type ProgressFn = Arc<dyn Fn(&str, f64) + Send + Sync>;

/// How much a log line matters: `-q` shows only errors, the default warnings and info, `-v`
/// debug detail too.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum LogLevel {
    /// Detail for `-v` (per-step numbers, solver internals).
    Debug,
    /// What a node did (`ctx.log`).
    Info,
    /// Something the user should look at (`ctx.log("warning: ...")`).
    Warning,
}

impl LogLevel {
    /// The level of a `ctx.log` line: lines starting with `warning` are warnings.
    pub fn of(line: &str) -> LogLevel {
        if line
            .trim_start()
            .to_ascii_lowercase()
            .starts_with("warning")
        {
            LogLevel::Warning
        } else {
            LogLevel::Info
        }
    }
}

/// Receives a node's log lines as they are written (node id, level, line), so a long node's
/// messages appear while it runs rather than at the end of the frame.
pub type LogFn = Arc<dyn Fn(&str, LogLevel, &str) + Send + Sync>;

/// `ExecContext::progress` with this value means "running, fraction unknown" (a spinner with
/// the elapsed time: plugins).
pub const PROGRESS_UNKNOWN: f64 = -1.0;

/// What a node's run left behind (`ExecContext::finish`).
pub struct Finished {
    /// Output values by socket.
    pub outputs: BTreeMap<String, Value>,
    /// Log lines.
    pub logs: Vec<String>,
    /// Files written, in order.
    pub written: Vec<PathBuf>,
    /// The values some of those files were written from (`ExecContext::wrote_from`).
    pub written_values: Vec<(PathBuf, Value)>,
}

/// What a runtime hands a node for one run, beside its id and declaration
/// (`ExecContext::for_run`).
pub struct RunSetup<'a> {
    /// Input values by socket, already converted to the sockets' types.
    pub inputs: BTreeMap<String, Value>,
    /// The frame being run.
    pub frame: i64,
    /// The node's state between frames.
    pub state: &'a mut Option<Box<dyn Any + Send>>,
    /// Where files are read and written.
    pub files: &'a FileEnv,
    /// Progress reports (0..1).
    pub progress: Option<ProgressFn>,
    /// Log lines as they are written.
    pub log_sink: Option<LogFn>,
    /// The outputs someone will read; `None` = all of them.
    pub wanted: Option<BTreeSet<String>>,
    /// The most bytes one buffer request may take.
    pub memory_limit: u64,
    /// What written files record about their origin.
    pub provenance: Option<Arc<Provenance>>,
}

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
    pub(crate) written_values: Vec<(PathBuf, Value)>,
    pub(crate) progress: Option<ProgressFn>,
    pub(crate) log_sink: Option<LogFn>,
    /// The outputs someone will read; `None` = all of them.
    pub(crate) wanted: Option<BTreeSet<String>>,
    /// The most bytes one buffer request may take (`reserve_bytes`).
    pub(crate) memory_limit: u64,
    /// What the files this node writes record about their origin; `None` (standalone use)
    /// writes them unchanged.
    pub(crate) provenance: Option<Arc<Provenance>>,
}

impl<'a> ExecContext<'a> {
    /// The context a runtime builds for one run of a node (see `RunSetup`).
    pub fn for_run(node_id: &'a str, decl: &'a NodeDecl, setup: RunSetup<'a>) -> ExecContext<'a> {
        ExecContext {
            node_id,
            decl,
            inputs: setup.inputs,
            outputs: BTreeMap::new(),
            frame: setup.frame,
            state: setup.state,
            files: setup.files,
            logs: Vec::new(),
            written: Vec::new(),
            written_values: Vec::new(),
            progress: setup.progress,
            log_sink: setup.log_sink,
            wanted: setup.wanted,
            memory_limit: setup.memory_limit,
            provenance: setup.provenance,
        }
    }

    /// Ends a run: the outputs set, the log lines written, the files written and the values
    /// they were written from.
    pub fn finish(&mut self) -> Finished {
        Finished {
            outputs: std::mem::take(&mut self.outputs),
            logs: std::mem::take(&mut self.logs),
            written: std::mem::take(&mut self.written),
            written_values: std::mem::take(&mut self.written_values),
        }
    }

    /// Records the value `path` was written from (a mesh, an image), so that the run report
    /// draws it without reading the file back (a writer node calls it after writing).
    pub fn wrote_from(&mut self, path: &Path, value: Value) {
        self.written_values.push((path.to_path_buf(), value));
    }

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
            written_values: Vec::new(),
            progress: None,
            log_sink: None,
            wanted: None,
            memory_limit: super::default_memory_limit(),
            provenance: None,
        }
    }

    /// Sets the provenance recorded in the files this context writes (standalone use; a run
    /// fills it from the graph).
    pub fn set_provenance(&mut self, p: Provenance) {
        self.provenance = Some(Arc::new(p));
    }

    /// The provenance recorded in the files this node writes, if any.
    pub fn provenance(&self) -> Option<&Provenance> {
        self.provenance.as_deref()
    }

    /// Sets the memory limit `reserve_bytes` checks against (standalone use; a run takes it
    /// from `RunOptions::max_memory`).
    pub fn set_memory_limit(&mut self, bytes: u64) {
        self.memory_limit = bytes;
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

    /// Writes a file atomically (temporary file in the same folder, then rename), with the
    /// provenance record embedded or beside it.
    pub fn write_file(&mut self, path: &Path, bytes: &[u8]) -> Result<(), NodeError> {
        let Some(p) = self.provenance.clone() else {
            crate::io::write_atomic(path, |w| w.write_all(bytes))
                .map_err(|e| NodeError::io(path, e))?;
            self.written.push(path.to_path_buf());
            return Ok(());
        };
        let embedded = crate::io::provenance::embed(path, bytes, &p.to_line());
        crate::io::write_atomic(path, |w| w.write_all(embedded.as_deref().unwrap_or(bytes)))
            .map_err(|e| NodeError::io(path, e))?;
        self.written.push(path.to_path_buf());
        if embedded.is_none() {
            self.write_sidecar(path, &p)?;
        }
        Ok(())
    }

    /// Writes a file atomically through a writer; on error nothing is left behind. With a
    /// provenance, the bytes are collected first so the record can be embedded.
    pub fn write_with(
        &mut self,
        path: &Path,
        f: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    ) -> Result<(), NodeError> {
        if self.provenance.is_none() {
            crate::io::write_atomic(path, f).map_err(|e| NodeError::io(path, e))?;
            self.written.push(path.to_path_buf());
            return Ok(());
        }
        let mut buf = Vec::new();
        f(&mut buf).map_err(|e| NodeError::io(path, e))?;
        self.write_file(path, &buf)
    }

    /// Records a file written by other means (already atomically), so the cache knows it,
    /// and adds the provenance record to it.
    pub fn record_written(&mut self, path: &Path) {
        self.written.push(path.to_path_buf());
        if let Some(p) = self.provenance.clone() {
            let ok = std::fs::read(path).ok().and_then(|bytes| {
                let b = crate::io::provenance::embed(path, &bytes, &p.to_line())?;
                crate::io::write_atomic(path, |w| w.write_all(&b)).ok()
            });
            if ok.is_none() {
                let _ = self.write_sidecar(path, &p);
            }
        }
    }

    /// Writes `FILE.provenance.json` beside `path`. It is not listed among the written files
    /// (run reports, the cache): it belongs to `path`.
    fn write_sidecar(&mut self, path: &Path, p: &Provenance) -> Result<(), NodeError> {
        let side = crate::io::provenance::sidecar_path(path);
        let text = serde_json::to_string_pretty(p).unwrap_or_default() + "\n";
        crate::io::write_atomic(&side, |w| w.write_all(text.as_bytes()))
            .map_err(|e| NodeError::io(&side, e))
    }

    /// The files written so far.
    pub fn written(&self) -> &[PathBuf] {
        &self.written
    }

    /// Adds a line to the run log.
    pub fn log(&mut self, msg: impl Into<String>) {
        let msg = msg.into();
        if let Some(sink) = &self.log_sink {
            sink(self.node_id, LogLevel::of(&msg), &msg);
        }
        self.logs.push(msg);
    }

    /// A detail line shown only with `-v`; not kept in the run report.
    pub fn debug(&self, msg: impl FnOnce() -> String) {
        if let Some(sink) = &self.log_sink {
            sink(self.node_id, LogLevel::Debug, &msg());
        }
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

    /// Reports that the node is busy for an unknown time (a spinner with the elapsed time);
    /// `progress(1.0)` ends it.
    pub fn progress_unknown(&self) {
        if let Some(p) = &self.progress {
            p(self.node_id, PROGRESS_UNKNOWN);
        }
    }

    /// A progress callback for loops that run on other threads or inside plain algorithm
    /// functions (fraction 0 to 1).
    pub fn progress_fn(&self) -> impl Fn(f64) + Send + Sync + 'static {
        let prog = self.progress.clone();
        let id = self.node_id.to_string();
        move |f: f64| {
            if let Some(p) = &prog {
                p(&id, f.clamp(0.0, 1.0));
            }
        }
    }

    /// The file environment.
    pub fn files(&self) -> &FileEnv {
        self.files
    }
}
