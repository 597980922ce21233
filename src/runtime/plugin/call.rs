//! One call of a plugin node: encodes the request (arrays as `.npy` files in a per-call
//! folder), runs the plugin's command with a time limit, and checks and decodes the
//! response; failures become node errors of kind `plugin` with the tail of stderr.

use super::{codec, process, PROTOCOL, TIMEOUT_SOCKET};
use cgnodes_api::node::{ErrorKind, ExecContext, FileRole, NodeDecl, NodeError};
use cgnodes_api::types::Value;
use serde_json::{json, Value as J};
use std::collections::BTreeMap;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

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

/// State kept between frames for a stateful plugin node: the JSON the plugin returned.
#[derive(Default)]
struct PluginState(Option<J>);

/// Runs a plugin node inside the executor.
pub(super) fn execute(
    r: &Runner,
    added_timeout: bool,
    ctx: &mut ExecContext,
) -> Result<(), NodeError> {
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
    ctx.progress_unknown();
    let res = call(r, decl, &inputs, ctx.frame(), state, timeout);
    ctx.progress(1.0);
    let res = res?;
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
    let fail = Fail {
        plugin: &r.plugin,
        stderr: None,
    };
    let t0 = Instant::now();
    // Registered so that Ctrl-C removes it (`io::interrupt`).
    let (_tracked, tmp) = cgnodes_api::io::interrupt::track(
        || tempfile::Builder::new().prefix("cgnodes-call-").tempdir(),
        |t| cgnodes_api::io::interrupt::Resource::Path(t.path().to_path_buf()),
    )
    .map_err(|e| fail.err(format!("cannot create the call folder: {e}")))?;
    let dir = tmp.path();
    let body = request(decl, inputs, dir, frame, state, &fail)?;
    let encode_ms = t0.elapsed().as_secs_f64() * 1e3;
    let proto = PROTOCOL.to_string();
    let env = [
        ("CGNODES_PROTOCOL", std::ffi::OsStr::new(&proto)),
        ("CGNODES_PLUGIN_DIR", r.dir.as_os_str()),
        ("CGNODES_CALL_DIR", dir.as_os_str()),
    ];
    let limit = Duration::from_secs_f64(timeout.clamp(0.001, 1e7));
    let fin = process::run(&r.argv, &r.dir, &env, body, limit).map_err(|e| fail.err(e))?;
    let t1 = Instant::now();
    let stderr = String::from_utf8_lossy(&fin.stderr).into_owned();
    let fail = Fail {
        plugin: &r.plugin,
        stderr: Some(&stderr),
    };
    let resp = response(&fin, timeout, &fail)?;
    let mut result = CallResult {
        outputs: decode_outputs(decl, &resp, dir, inputs, &fail)?,
        logs: logs(&resp, &stderr),
        state: resp.get("state").cloned(),
        stats: CallStats::default(),
    };
    result.stats = CallStats {
        encode_ms,
        spawn_ms: fin.spawn_ms,
        run_ms: fin.run_ms,
        decode_ms: t1.elapsed().as_secs_f64() * 1e3,
    };
    Ok(result)
}

/// Makes a plugin call's node errors: `plugin 'NAME': ...`, with the tail of stderr once the
/// process ran.
struct Fail<'a> {
    plugin: &'a str,
    stderr: Option<&'a str>,
}

impl Fail<'_> {
    fn err(&self, msg: impl std::fmt::Display) -> NodeError {
        let tail = self.stderr.map(stderr_tail).unwrap_or_default();
        NodeError::new(
            ErrorKind::Plugin,
            format!("plugin '{}': {msg}{tail}", self.plugin),
        )
    }
}

/// The request's bytes: the inputs encoded into `dir`, the outputs wanted, the state.
fn request(
    decl: &NodeDecl,
    inputs: &BTreeMap<String, Value>,
    dir: &Path,
    frame: i64,
    state: Option<J>,
    fail: &Fail,
) -> Result<Vec<u8>, NodeError> {
    let mut enc = serde_json::Map::new();
    for (name, v) in inputs {
        let j = codec::encode(v, dir, &format!("in.{name}"))
            .map_err(|e| fail.err(format!("input '{name}': {e}")))?;
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
    serde_json::to_vec(&req).map_err(|e| fail.err(e))
}

/// The response of a process that ran: it did not time out, report an error or fail, and
/// its stdout is JSON of this protocol.
fn response(fin: &process::Finished, timeout: f64, fail: &Fail) -> Result<J, NodeError> {
    let Some(status) = fin.status else {
        return Err(fail.err(format!("timed out after {timeout} s and was killed")));
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
        return Err(fail.err(format!("reported an error: {msg}")));
    }
    if !status.success() {
        return Err(fail.err(format!("exited with {}", describe_status(&status))));
    }
    let Some(resp) = resp else {
        let out = String::from_utf8_lossy(&fin.stdout);
        let shown: String = out.chars().take(200).collect();
        let nan = if out.contains("NaN") || out.contains("Infinity") {
            " (NaN and Infinity are not JSON numbers)"
        } else {
            ""
        };
        return Err(fail.err(format!(
            "the response on stdout is not JSON{nan} (log lines go to stderr): {:?}{}",
            shown,
            if out.chars().count() > 200 { "..." } else { "" }
        )));
    };
    match resp.get("protocol").and_then(J::as_u64) {
        Some(v) if v == PROTOCOL as u64 => Ok(resp),
        other => Err(fail.err(format!(
            "the response should carry \"protocol\": {PROTOCOL}, got {}",
            other
                .map(|v| v.to_string())
                .unwrap_or_else(|| "none".into())
        ))),
    }
}

/// The response's outputs, each declared and decoded to its socket's type; every output
/// that is not optional present.
fn decode_outputs(
    decl: &NodeDecl,
    resp: &J,
    dir: &Path,
    inputs: &BTreeMap<String, Value>,
    fail: &Fail,
) -> Result<BTreeMap<String, Value>, NodeError> {
    let outs = resp
        .get("outputs")
        .and_then(J::as_object)
        .ok_or_else(|| fail.err("the response has no \"outputs\" object"))?;
    if let Some(name) = outs.keys().find(|name| decl.output(name).is_none()) {
        return Err(fail.err(format!(
            "returned output '{name}', which the manifest does not declare"
        )));
    }
    let mut outputs = BTreeMap::new();
    for o in &decl.outputs {
        match outs.get(&o.name) {
            None | Some(J::Null) if o.optional => {}
            None | Some(J::Null) => {
                return Err(fail.err(format!("returned no output '{}'", o.name)))
            }
            Some(j) => {
                let v = codec::decode(&o.ty, j, dir, inputs)
                    .map_err(|e| fail.err(format!("output '{}' ({}): {e}", o.name, o.ty)))?;
                outputs.insert(o.name.clone(), v);
            }
        }
    }
    Ok(outputs)
}

/// Log lines: the response's `log`, then the last 20 non-empty lines of stderr.
fn logs(resp: &J, stderr: &str) -> Vec<String> {
    let mut logs = Vec::new();
    match resp.get("log") {
        Some(J::Array(lines)) => logs.extend(lines.iter().map(|l| {
            l.as_str()
                .map(String::from)
                .unwrap_or_else(|| l.to_string())
        })),
        Some(J::String(s)) => logs.extend(s.lines().map(String::from)),
        _ => {}
    }
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    let skip = lines.len().saturating_sub(20);
    if skip > 0 {
        logs.push(format!("({skip} earlier stderr lines not shown)"));
    }
    logs.extend(lines[skip..].iter().map(|l| l.to_string()));
    logs
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
