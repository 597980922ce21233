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

pub mod codec;
pub mod npy;
mod process;

use crate::node::{ErrorKind, ExecContext, FileRole, NodeDecl, NodeError, SocketDecl};
use crate::registry::Registry;
use crate::types::{SocketType, Value};
use serde::Deserialize;
use serde_json::{json, Value as J};
use std::collections::BTreeMap;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

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

/// A plugin manifest (`cgnodes-plugin.json`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// Plugin name.
    pub name: String,
    /// Plugin version (free text; part of the nodes' cache key).
    #[serde(default)]
    pub version: String,
    /// One-line description.
    #[serde(default)]
    pub doc: String,
    /// The protocol version the plugin speaks (1).
    pub protocol: u32,
    /// The program and its arguments. A program given with a `/` is relative to the plugin
    /// folder; a bare name (`python3`) is looked up in `PATH`. The command runs in the plugin
    /// folder.
    pub command: Vec<String>,
    /// Default time limit per call in seconds.
    #[serde(default)]
    pub timeout: Option<f64>,
    /// The nodes, in the schema `cgnodes nodes --json` prints.
    pub nodes: Vec<NodeDecl>,
}

/// A loaded plugin: where it lives, how to run it, and its node declarations.
#[derive(Clone, Debug)]
pub struct Plugin {
    /// Plugin name.
    pub name: String,
    /// Plugin version.
    pub version: String,
    /// The plugin folder (absolute).
    pub dir: PathBuf,
    /// The resolved command.
    pub argv: Vec<OsString>,
    /// Default time limit per call in seconds.
    pub timeout: f64,
    /// The nodes, ready to register.
    pub nodes: Vec<NodeDecl>,
}

impl Plugin {
    /// What `call` needs to run this plugin's nodes.
    pub fn runner(&self) -> Runner {
        Runner {
            plugin: self.name.clone(),
            dir: self.dir.clone(),
            argv: self.argv.clone(),
            timeout: self.timeout,
        }
    }

    /// The declaration of node `type_name`.
    pub fn node(&self, type_name: &str) -> Option<&NodeDecl> {
        self.nodes.iter().find(|d| d.type_name == type_name)
    }
}

/// What a call to a plugin node needs besides its inputs.
#[derive(Clone, Debug)]
pub struct Runner {
    /// Plugin name (for messages).
    pub plugin: String,
    /// Plugin folder; the command runs there.
    pub dir: PathBuf,
    /// The command.
    pub argv: Vec<OsString>,
    /// Default time limit in seconds.
    pub timeout: f64,
}

/// Time spent in each phase of a plugin call, in milliseconds.
#[derive(Clone, Copy, Debug, Default)]
pub struct CallStats {
    /// Writing the request and its `.npy` files.
    pub encode_ms: f64,
    /// Starting the process.
    pub spawn_ms: f64,
    /// From start to exit of the process (includes `spawn_ms`).
    pub run_ms: f64,
    /// Parsing the response and reading its `.npy` files.
    pub decode_ms: f64,
}

/// The result of a successful plugin call.
#[derive(Clone, Debug, Default)]
pub struct CallResult {
    /// Output values by socket.
    pub outputs: BTreeMap<String, Value>,
    /// Log lines: the response's `log`, then stderr.
    pub logs: Vec<String>,
    /// The state the plugin returned (stateful nodes).
    pub state: Option<J>,
    /// Where the time went.
    pub stats: CallStats,
}

/// Reads and checks the manifest in `dir`; the nodes run the plugin's command.
pub fn load(dir: &Path) -> Result<Plugin, String> {
    let file = dir.join(MANIFEST);
    let text = std::fs::read_to_string(&file).map_err(|e| format!("{}: {e}", file.display()))?;
    let m: Manifest =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", file.display()))?;
    let dir = std::path::absolute(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let err = |msg: String| format!("{}: {msg}", file.display());
    if m.protocol != PROTOCOL {
        return Err(err(format!(
            "plugin '{}' speaks protocol {}, this cgnodes speaks {PROTOCOL}",
            m.name, m.protocol
        )));
    }
    if !is_name(&m.name) {
        return Err(err(format!(
            "plugin name '{}' should be snake_case letters, digits and '_'",
            m.name
        )));
    }
    let Some((prog, args)) = m.command.split_first() else {
        return Err(err("'command' is empty".into()));
    };
    let prog_os: OsString = if prog.contains('/') {
        if Path::new(prog).is_absolute() {
            prog.into()
        } else {
            dir.join(prog).into_os_string()
        }
    } else {
        prog.into()
    };
    let mut argv = vec![prog_os];
    argv.extend(args.iter().map(OsString::from));
    let timeout = m.timeout.unwrap_or(DEFAULT_TIMEOUT_S);
    if !(timeout.is_finite() && timeout > 0.0) {
        return Err(err(format!(
            "'timeout' must be a positive number of seconds, got {timeout}"
        )));
    }
    let runner = Arc::new(Runner {
        plugin: m.name.clone(),
        dir: dir.clone(),
        argv: argv.clone(),
        timeout,
    });
    // The source enters the nodes' cache keys: the stamp makes a changed script miss the
    // disk cache.
    let source = format!(
        "plugin {}{} ({}) #{}",
        m.name,
        if m.version.is_empty() {
            String::new()
        } else {
            format!(" {}", m.version)
        },
        dir.display(),
        folder_stamp(&dir)
    );
    let mut nodes = Vec::new();
    for mut d in m.nodes {
        check_decl(&d).map_err(|e| err(format!("node '{}': {e}", d.type_name)))?;
        let added_timeout = d.input(TIMEOUT_SOCKET).is_none();
        if added_timeout {
            d.inputs.push(SocketDecl {
                name: TIMEOUT_SOCKET.into(),
                ty: SocketType::Float,
                doc: "Seconds before the plugin process is killed.".into(),
                default: Some(json!(timeout)),
                min: Some(0.001),
                max: None,
                choices: None,
                optional: false,
                file: FileRole::None,
            });
        }
        d.source = source.clone();
        if d.category.is_empty() {
            d.category = "plugin".into();
        }
        let r = runner.clone();
        d.exec = Some(Arc::new(move |ctx: &mut ExecContext| {
            execute(&r, added_timeout, ctx)
        }));
        nodes.push(d);
    }
    Ok(Plugin {
        name: m.name,
        version: m.version,
        dir,
        argv,
        timeout,
        nodes,
    })
}

/// A short hash of the names, sizes and modification times of the files at the top of a
/// plugin folder: it changes when the plugin's scripts are edited.
fn folder_stamp(dir: &Path) -> String {
    let mut files: Vec<(String, u64, u128)> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .filter_map(|e| {
                    let m = e.metadata().ok().filter(|m| m.is_file())?;
                    let t = m
                        .modified()
                        .ok()
                        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
                        .map_or(0, |d| d.as_nanos());
                    Some((e.file_name().to_string_lossy().into_owned(), m.len(), t))
                })
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    let mut h = blake3::Hasher::new();
    for (name, len, t) in files {
        h.update(name.as_bytes());
        h.update(&len.to_le_bytes());
        h.update(&t.to_le_bytes());
    }
    h.finalize().to_hex()[..8].to_string()
}

fn is_name(s: &str) -> bool {
    !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
        && !s.starts_with(|c: char| c.is_ascii_digit())
}

/// Checks a node declaration from a manifest: names, unique sockets, types the protocol
/// carries, defaults of the socket's type.
fn check_decl(d: &NodeDecl) -> Result<(), String> {
    if !is_name(&d.type_name) {
        return Err("the type name should be snake_case letters, digits and '_'".into());
    }
    for (side, list) in [("input", &d.inputs), ("output", &d.outputs)] {
        let mut seen = std::collections::BTreeSet::new();
        for s in list.iter() {
            if !is_name(&s.name) {
                return Err(format!("{side} '{}': socket names are snake_case", s.name));
            }
            if !seen.insert(&s.name) {
                return Err(format!("{side} '{}' is declared twice", s.name));
            }
            if !codec::supported(&s.ty) {
                return Err(format!(
                    "{side} '{}': {} values cannot cross the plugin boundary",
                    s.name, s.ty
                ));
            }
            if let Some(j) = &s.default {
                let v = Value::from_json(&s.ty, j)
                    .map_err(|e| format!("{side} '{}': default: {e}", s.name))?;
                s.check_literal(&v)
                    .map_err(|e| format!("{side} '{}': default: {e}", s.name))?;
            }
            if s.file != FileRole::None && s.ty != SocketType::String {
                return Err(format!(
                    "{side} '{}': only string sockets name files",
                    s.name
                ));
            }
        }
    }
    if let Some(t) = d.input(TIMEOUT_SOCKET) {
        if t.ty != SocketType::Float {
            return Err(format!(
                "input '{TIMEOUT_SOCKET}' is the call's time limit and must be a float"
            ));
        }
    }
    Ok(())
}

/// State kept between frames for a stateful plugin node: the JSON the plugin returned.
#[derive(Default)]
struct PluginState(Option<J>);

/// Runs a plugin node inside the executor.
fn execute(r: &Runner, added_timeout: bool, ctx: &mut ExecContext) -> Result<(), NodeError> {
    let decl = ctx.decl;
    let timeout: f64 = ctx.input(TIMEOUT_SOCKET)?;
    let mut inputs = BTreeMap::new();
    let mut written = Vec::new();
    for s in &decl.inputs {
        if added_timeout && s.name == TIMEOUT_SOCKET {
            continue;
        }
        let Some(v) = ctx.input_value(&s.name).cloned() else {
            continue;
        };
        // File sockets travel as absolute paths: the plugin runs in its own folder.
        let v = match (s.file, &v) {
            (FileRole::Input, Value::String(p)) => Value::String(abs(&ctx.input_path(p))),
            (FileRole::Output, Value::String(p)) => {
                let path = ctx.output_path(&s.name, p)?;
                if let Some(parent) = path.parent() {
                    std::fs::create_dir_all(parent).map_err(|e| NodeError::io(parent, e))?;
                }
                written.push(path.clone());
                Value::String(abs(&path))
            }
            _ => v,
        };
        inputs.insert(s.name.clone(), v);
    }
    let state = if decl.stateful {
        ctx.state::<PluginState>()?.0.take()
    } else {
        None
    };
    let res = call(r, decl, &inputs, ctx.frame(), state, timeout)?;
    if decl.stateful {
        ctx.state::<PluginState>()?.0 = res.state;
    }
    for l in res.logs {
        ctx.log(l);
    }
    let s = res.stats;
    ctx.log(format!(
        "plugin call: write {:.1} ms, process {:.1} ms (start {:.1} ms), read {:.1} ms",
        s.encode_ms, s.run_ms, s.spawn_ms, s.decode_ms
    ));
    for p in written {
        if p.exists() {
            ctx.record_written(&p);
        }
    }
    for (k, v) in res.outputs {
        ctx.set_output(&k, v);
    }
    Ok(())
}

fn abs(p: &Path) -> String {
    std::path::absolute(p)
        .unwrap_or_else(|_| p.to_path_buf())
        .to_string_lossy()
        .into_owned()
}

/// Calls plugin node `decl` once, outside the executor: writes the request, runs the
/// command with a time limit of `timeout` seconds, checks and decodes the response.
/// `inputs` are sent as they are (file paths should already be absolute).
pub fn call(
    r: &Runner,
    decl: &NodeDecl,
    inputs: &BTreeMap<String, Value>,
    frame: i64,
    state: Option<J>,
    timeout: f64,
) -> Result<CallResult, NodeError> {
    let fail =
        |msg: String| NodeError::new(ErrorKind::Plugin, format!("plugin '{}': {msg}", r.plugin));
    let t0 = Instant::now();
    let tmp = tempfile::Builder::new()
        .prefix("cgnodes-call-")
        .tempdir()
        .map_err(|e| fail(format!("cannot create the call folder: {e}")))?;
    let dir = tmp.path();
    let mut enc = serde_json::Map::new();
    for (name, v) in inputs {
        let j = codec::encode(v, dir, &format!("in.{name}"))
            .map_err(|e| fail(format!("input '{name}': {e}")))?;
        enc.insert(name.clone(), j);
    }
    let outputs: Vec<J> = decl
        .outputs
        .iter()
        .map(|o| json!({"name": o.name, "type": o.ty}))
        .collect();
    let mut req = json!({
        "protocol": PROTOCOL,
        "node": decl.type_name,
        "frame": frame,
        "call_dir": dir.to_string_lossy(),
        "inputs": enc,
        "outputs": outputs,
    });
    if decl.stateful {
        req["state"] = state.unwrap_or(J::Null);
    }
    let body = serde_json::to_vec(&req).map_err(|e| fail(e.to_string()))?;
    let encode_ms = t0.elapsed().as_secs_f64() * 1e3;
    let proto = PROTOCOL.to_string();
    let env = [
        ("CGNODES_PROTOCOL", std::ffi::OsStr::new(&proto)),
        ("CGNODES_PLUGIN_DIR", r.dir.as_os_str()),
        ("CGNODES_CALL_DIR", dir.as_os_str()),
    ];
    let limit = Duration::from_secs_f64(timeout.clamp(0.001, 1e7));
    let fin = process::run(&r.argv, &r.dir, &env, body, limit).map_err(fail)?;
    let t1 = Instant::now();
    let stderr = String::from_utf8_lossy(&fin.stderr).into_owned();
    let with_tail = |msg: String| fail(format!("{msg}{}", stderr_tail(&stderr)));
    let status = match fin.status {
        None => {
            return Err(with_tail(format!(
                "timed out after {timeout} s and was killed"
            )))
        }
        Some(s) => s,
    };
    // A response that parses is read even after a failure exit: it may carry the
    // plugin's own error message.
    let resp: Option<J> = serde_json::from_slice(&fin.stdout).ok();
    if let Some(msg) = resp
        .as_ref()
        .and_then(|j| j.get("error"))
        .filter(|e| !e.is_null())
    {
        let msg = msg
            .as_str()
            .map(String::from)
            .unwrap_or_else(|| msg.to_string());
        return Err(with_tail(format!("reported an error: {msg}")));
    }
    if !status.success() {
        return Err(with_tail(format!(
            "exited with {}",
            describe_status(&status)
        )));
    }
    let Some(resp) = resp else {
        let out = String::from_utf8_lossy(&fin.stdout);
        let shown: String = out.chars().take(200).collect();
        let nan = if out.contains("NaN") || out.contains("Infinity") {
            " (NaN and Infinity are not JSON numbers)"
        } else {
            ""
        };
        return Err(with_tail(format!(
            "the response on stdout is not JSON{nan} (log lines go to stderr): {:?}{}",
            shown,
            if out.chars().count() > 200 { "..." } else { "" }
        )));
    };
    match resp.get("protocol").and_then(J::as_u64) {
        Some(v) if v == PROTOCOL as u64 => {}
        other => {
            return Err(with_tail(format!(
                "the response should carry \"protocol\": {PROTOCOL}, got {}",
                other
                    .map(|v| v.to_string())
                    .unwrap_or_else(|| "none".into())
            )))
        }
    }
    let outs = resp
        .get("outputs")
        .and_then(J::as_object)
        .ok_or_else(|| with_tail("the response has no \"outputs\" object".into()))?;
    let mut result = CallResult::default();
    for name in outs.keys() {
        if decl.output(name).is_none() {
            return Err(with_tail(format!(
                "returned output '{name}', which the manifest does not declare"
            )));
        }
    }
    for o in &decl.outputs {
        match outs.get(&o.name) {
            None | Some(J::Null) if o.optional => {}
            None | Some(J::Null) => {
                return Err(with_tail(format!("returned no output '{}'", o.name)))
            }
            Some(j) => {
                let v = codec::decode(&o.ty, j, dir, inputs)
                    .map_err(|e| with_tail(format!("output '{}' ({}): {e}", o.name, o.ty)))?;
                result.outputs.insert(o.name.clone(), v);
            }
        }
    }
    if let Some(log) = resp.get("log") {
        match log {
            J::Array(lines) => result.logs.extend(lines.iter().map(|l| {
                l.as_str()
                    .map(String::from)
                    .unwrap_or_else(|| l.to_string())
            })),
            J::String(s) => result.logs.extend(s.lines().map(String::from)),
            _ => {}
        }
    }
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    let skip = lines.len().saturating_sub(20);
    if skip > 0 {
        result
            .logs
            .push(format!("({skip} earlier stderr lines not shown)"));
    }
    result
        .logs
        .extend(lines[skip..].iter().map(|l| l.to_string()));
    result.state = resp.get("state").cloned();
    result.stats = CallStats {
        encode_ms,
        spawn_ms: fin.spawn_ms,
        run_ms: fin.run_ms,
        decode_ms: t1.elapsed().as_secs_f64() * 1e3,
    };
    Ok(result)
}

fn describe_status(s: &std::process::ExitStatus) -> String {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(sig) = s.signal() {
            return format!("signal {sig}");
        }
    }
    match s.code() {
        Some(c) => format!("status {c}"),
        None => "an unknown status".into(),
    }
}

/// The last lines of a plugin's stderr, for error messages.
fn stderr_tail(stderr: &str) -> String {
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    if lines.is_empty() {
        return " (stderr was empty)".into();
    }
    let keep = &lines[lines.len().saturating_sub(15)..];
    let mut s = keep.join("\n");
    if s.len() > 3000 {
        let cut = s.len() - 3000;
        let cut = (cut..s.len())
            .find(|&i| s.is_char_boundary(i))
            .unwrap_or(cut);
        s = format!("...{}", &s[cut..]);
    }
    format!("\n--- plugin stderr (last {} lines) ---\n{s}", keep.len())
}

/// The user's plugin folder: `$XDG_CONFIG_HOME/cgnodes/plugins`, else
/// `$HOME/.config/cgnodes/plugins`.
pub fn user_dir() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CONFIG_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("HOME")
                .filter(|v| !v.is_empty())
                .map(|h| PathBuf::from(h).join(".config"))
        })?;
    Some(base.join("cgnodes").join("plugins"))
}

/// Where a plugin search folder comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    /// `--plugins DIR` (must exist).
    Cli,
    /// `CGNODES_PLUGIN_PATH`.
    Env,
    /// The user's config folder (need not exist).
    User,
}

/// The folders searched for plugins, in order of precedence: the `--plugins` folders (which
/// must exist), then `CGNODES_PLUGIN_PATH`, then the user's folder. Each is either a plugin
/// folder (it holds a manifest) or a folder of plugin folders.
pub fn search_path(
    cli: &[PathBuf],
    env_path: Option<&std::ffi::OsStr>,
    user: Option<PathBuf>,
) -> Vec<(PathBuf, Origin)> {
    let mut v: Vec<(PathBuf, Origin)> = cli.iter().map(|p| (p.clone(), Origin::Cli)).collect();
    if let Some(e) = env_path {
        v.extend(
            std::env::split_paths(e)
                .filter(|p| !p.as_os_str().is_empty())
                .map(|p| (p, Origin::Env)),
        );
    }
    if let Some(u) = user {
        v.push((u, Origin::User));
    }
    v
}

/// The plugin folders under `root`: `root` itself if it holds a manifest, else its
/// subfolders that do, sorted by name.
pub fn discover(root: &Path) -> Result<Vec<PathBuf>, String> {
    if root.join(MANIFEST).is_file() {
        return Ok(vec![root.to_path_buf()]);
    }
    let rd = std::fs::read_dir(root).map_err(|e| format!("{}: {e}", root.display()))?;
    let mut v: Vec<PathBuf> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join(MANIFEST).is_file())
        .collect();
    v.sort();
    Ok(v)
}

/// Adds the nodes of plugin `p` to `registry`. A node whose name is taken (a built-in node or
/// an earlier plugin's) is not added; the returned warnings say so.
pub fn register(registry: &mut Registry, p: Plugin) -> Vec<String> {
    let mut warnings = Vec::new();
    for d in p.nodes {
        if let Some(old) = registry.get(&d.type_name) {
            warnings.push(format!(
                "plugin '{}' at {}: node '{}' is not added; the name is taken by {}",
                p.name,
                p.dir.display(),
                d.type_name,
                old.source
            ));
            continue;
        }
        registry.add_decl(d);
    }
    warnings
}

/// Adds every plugin found on the search path to `registry`. Fails when a `--plugins`
/// folder does not exist; other problems (a broken manifest, a taken name, a missing
/// folder on `CGNODES_PLUGIN_PATH`) are returned as warnings and the plugin is skipped.
pub fn load_all(
    registry: &mut Registry,
    search: &[(PathBuf, Origin)],
) -> Result<Vec<String>, String> {
    let mut warnings = Vec::new();
    for (root, origin) in search {
        let explicit = &(*origin == Origin::Cli);
        if !root.exists() {
            match origin {
                Origin::Cli => return Err(format!("--plugins {}: no such folder", root.display())),
                Origin::Env => {
                    warnings.push(format!("{PATH_VAR}: {}: no such folder", root.display()))
                }
                Origin::User => {}
            }
            continue;
        }
        let dirs = match discover(root) {
            Ok(d) => d,
            Err(e) if *explicit => return Err(e),
            Err(e) => {
                warnings.push(e);
                continue;
            }
        };
        if dirs.is_empty() && *explicit {
            return Err(format!(
                "--plugins {}: neither a plugin folder (no {MANIFEST}) nor a folder of plugins",
                root.display()
            ));
        }
        for d in dirs {
            match load(&d) {
                Ok(p) => warnings.extend(register(registry, p)),
                Err(e) => warnings.push(format!("plugin not loaded: {e}")),
            }
        }
    }
    Ok(warnings)
}

/// The registry the command line uses: `base` plus the plugins from `--plugins` folders,
/// `CGNODES_PLUGIN_PATH` and the user's folder. Warnings go to stderr.
pub fn cli_registry(base: Registry, cli_dirs: &[PathBuf]) -> Result<Registry, String> {
    let mut r = base;
    let search = search_path(cli_dirs, std::env::var_os(PATH_VAR).as_deref(), user_dir());
    for w in load_all(&mut r, &search)? {
        eprintln!("warning: {w}");
    }
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn search_order_is_cli_then_env_then_user() {
        let env = std::env::join_paths(["/a", "/b"]).unwrap();
        let s = search_path(
            &[PathBuf::from("/cli")],
            Some(&env),
            Some(PathBuf::from("/home/u/.config/cgnodes/plugins")),
        );
        let names: Vec<_> = s.iter().map(|(p, o)| (p.to_str().unwrap(), *o)).collect();
        assert_eq!(
            names,
            [
                ("/cli", Origin::Cli),
                ("/a", Origin::Env),
                ("/b", Origin::Env),
                ("/home/u/.config/cgnodes/plugins", Origin::User)
            ]
        );
    }

    #[test]
    fn manifests_are_checked() {
        let d = tempfile::tempdir().unwrap();
        let write = |text: &str| std::fs::write(d.path().join(MANIFEST), text).unwrap();
        write(r#"{"name": "p", "protocol": 2, "command": ["x"], "nodes": []}"#);
        assert!(load(d.path()).unwrap_err().contains("protocol 2"));
        write(r#"{"name": "p", "protocol": 1, "command": [], "nodes": []}"#);
        assert!(load(d.path()).unwrap_err().contains("empty"));
        write(r#"{"name": "p", "protocol": 1, "command": ["x"], "nodes": [], "shell": "rm"}"#);
        assert!(load(d.path()).unwrap_err().contains("unknown field"));
        write(
            r#"{"name": "p", "protocol": 1, "command": ["x"], "nodes": [
               {"type": "n", "inputs": [{"name": "s", "type": "scene"}]}]}"#,
        );
        assert!(load(d.path()).unwrap_err().contains("cannot cross"));
        write(
            r#"{"name": "p", "protocol": 1, "command": ["x"], "nodes": [
               {"type": "n", "inputs": [{"name": "k", "type": "int", "default": 2.5}]}]}"#,
        );
        assert!(load(d.path()).unwrap_err().contains("default"));
        write(
            r#"{"name": "p", "protocol": 1, "command": ["bin/run"], "timeout": 5, "nodes": [
               {"type": "n", "inputs": [{"name": "k", "type": "int", "default": 2}],
                "outputs": [{"name": "v", "type": "float"}]}]}"#,
        );
        let p = load(d.path()).unwrap();
        assert!(Path::new(&p.argv[0]).is_absolute());
        let n = &p.nodes[0];
        assert!(n.source.starts_with("plugin p ("));
        let t = n.input(TIMEOUT_SOCKET).unwrap();
        assert_eq!(t.default, Some(json!(5.0)));
    }

    #[test]
    fn plugins_do_not_replace_builtin_nodes() {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(
            d.path().join(MANIFEST),
            r#"{"name": "p", "protocol": 1, "command": ["x"], "nodes": [{"type": "math"}]}"#,
        )
        .unwrap();
        let mut r = Registry::new();
        r.add("math", |_| {}, |_| Ok(()));
        let w = load_all(&mut r, &[(d.path().to_path_buf(), Origin::Cli)]).unwrap();
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(r.get("math").unwrap().source, "builtin");
        assert!(load_all(&mut r, &[(d.path().join("nope"), Origin::Cli)]).is_err());
    }
}
