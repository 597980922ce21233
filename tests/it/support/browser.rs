//! Headless Debian chromium driven through the DevTools protocol over a pipe
//! (`--remote-debugging-pipe`: JSON messages ending in a NUL byte, commands on the child's
//! fd 3, answers and events on its fd 4), and a `cgnodes serve` process to point it at: for
//! the tests of `serve`'s page and its benchmark (`bench/serve_loop.rs` includes this file).
//! No WebSocket client needed.

use serde_json::{json, Value as Json};
use std::fs::File;
use std::io::{BufRead, BufReader, Write};
use std::os::fd::{FromRawFd, RawFd};
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A running headless chromium with one page attached.
pub struct Browser {
    child: Child,
    commands: File,
    answers: BufReader<File>,
    next_id: u64,
    session: Option<String>,
    _profile: tempfile::TempDir,
}

/// Whether `chromium` can be started.
pub fn chromium_available() -> bool {
    Command::new("chromium")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

fn pipe() -> (RawFd, RawFd) {
    let mut fds = [0; 2];
    // SAFETY: `fds` has room for the two descriptors pipe2 writes.
    let r = unsafe { libc::pipe2(fds.as_mut_ptr(), libc::O_CLOEXEC) };
    assert_eq!(r, 0, "pipe2 failed");
    // Moved above 10 so that the child's dup2 onto 3 and 4 cannot overwrite one of them.
    let high = |fd: RawFd| {
        // SAFETY: duplicating a descriptor this function owns.
        let h = unsafe { libc::fcntl(fd, libc::F_DUPFD_CLOEXEC, 10) };
        // SAFETY: closing the original, now duplicated.
        unsafe { libc::close(fd) };
        h
    };
    (high(fds[0]), high(fds[1]))
}

impl Browser {
    /// Starts chromium (software WebGL through SwiftShader) with an empty profile.
    pub fn launch() -> Browser {
        let profile = tempfile::tempdir().unwrap();
        let (cmd_r, cmd_w) = pipe();
        let (ans_r, ans_w) = pipe();
        let mut c = Command::new("chromium");
        c.args([
            "--headless",
            "--no-sandbox",
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--remote-debugging-pipe",
            "--window-size=1280,1400",
            "--no-first-run",
            "--disable-extensions",
        ])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .arg("about:blank")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null());
        // SAFETY: only async-signal-safe calls (dup2) between fork and exec.
        unsafe {
            c.pre_exec(move || {
                if libc::dup2(cmd_r, 3) < 0 || libc::dup2(ans_w, 4) < 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
        let child = c.spawn().expect("chromium starts");
        // SAFETY: the parent's ends, owned from here on; the child's ends are closed here.
        let (commands, answers) = unsafe {
            libc::close(cmd_r);
            libc::close(ans_w);
            (File::from_raw_fd(cmd_w), File::from_raw_fd(ans_r))
        };
        Browser {
            child,
            commands,
            answers: BufReader::new(answers),
            next_id: 1,
            session: None,
            _profile: profile,
        }
    }

    /// Sends a command (to the attached page once there is one) and waits for its answer;
    /// events in between are dropped.
    pub fn call(&mut self, method: &str, params: Json) -> Result<Json, String> {
        let id = self.next_id;
        self.next_id += 1;
        let mut msg = json!({ "id": id, "method": method, "params": params });
        if let Some(s) = &self.session {
            msg["sessionId"] = json!(s);
        }
        let mut bytes = msg.to_string().into_bytes();
        bytes.push(0);
        self.commands
            .write_all(&bytes)
            .map_err(|e| format!("chromium went away: {e}"))?;
        loop {
            let mut buf = Vec::new();
            let n = self
                .answers
                .read_until(0, &mut buf)
                .map_err(|e| e.to_string())?;
            if n == 0 {
                return Err("chromium closed the pipe".into());
            }
            buf.pop();
            let v: Json = serde_json::from_slice(&buf).map_err(|e| e.to_string())?;
            if v["id"] == json!(id) {
                if let Some(e) = v.get("error") {
                    return Err(format!("{method}: {e}"));
                }
                return Ok(v["result"].clone());
            }
        }
    }

    /// Opens `url` in a new page and attaches to it.
    pub fn open(&mut self, url: &str) -> Result<(), String> {
        self.session = None;
        let t = self.call("Target.createTarget", json!({ "url": url }))?;
        let a = self.call(
            "Target.attachToTarget",
            json!({ "targetId": t["targetId"], "flatten": true }),
        )?;
        self.session = a["sessionId"].as_str().map(String::from);
        self.call("Runtime.enable", json!({}))?;
        Ok(())
    }

    /// Evaluates `expr` in the page (awaiting a promise) and returns its value.
    pub fn eval(&mut self, expr: &str) -> Result<Json, String> {
        let r = self.call(
            "Runtime.evaluate",
            json!({ "expression": expr, "awaitPromise": true, "returnByValue": true }),
        )?;
        if let Some(e) = r.get("exceptionDetails") {
            return Err(format!("{expr}: {e}"));
        }
        Ok(r["result"]["value"].clone())
    }

    /// Evaluates `expr` every 25 ms until it is truthy (`Ok` with its value) or `timeout`
    /// passes (`Err` with the last value).
    pub fn wait_for(&mut self, expr: &str, timeout: Duration) -> Result<Json, String> {
        let t0 = Instant::now();
        loop {
            let v = self.eval(expr)?;
            let truthy =
                !matches!(v, Json::Null | Json::Bool(false)) && v != json!(0) && v != json!("");
            if truthy {
                return Ok(v);
            }
            if t0.elapsed() > timeout {
                return Err(format!("timed out waiting for {expr} (last: {v})"));
            }
            std::thread::sleep(Duration::from_millis(25));
        }
    }

    /// A PNG screenshot of the page, base64-encoded as the protocol gives it (for
    /// `bench/serve_loop.rs`, which includes this file, and the README's screenshot).
    #[allow(dead_code)]
    pub fn screenshot_base64(&mut self, full_page: bool) -> Result<String, String> {
        let r = self.call(
            "Page.captureScreenshot",
            json!({ "format": "png", "captureBeyondViewport": full_page }),
        )?;
        r["data"]
            .as_str()
            .map(String::from)
            .ok_or_else(|| "no screenshot data".into())
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A `cgnodes serve` process on a free port; killed when dropped.
pub struct Served {
    child: Child,
    /// The URL it printed, with its token.
    pub url: String,
    /// Its port.
    #[allow(dead_code)]
    pub port: u16,
    /// Its token.
    #[allow(dead_code)]
    pub token: String,
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts `cgnodes serve graph --out out --port 0` and reads the URL it prints.
pub fn serve(graph: &Path, out: &Path) -> Served {
    let mut child = Command::new(env!("CARGO_BIN_EXE_cgnodes"))
        .arg("serve")
        .arg(graph)
        .arg("--out")
        .arg(out)
        .args(["--port", "0", "--quiet"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let url = line.trim().to_string();
    let rest = url.strip_prefix("http://127.0.0.1:").expect("a local URL");
    let port = rest.split('/').next().unwrap().parse().unwrap();
    let token = url.split("token=").nth(1).unwrap().to_string();
    Served {
        child,
        url,
        port,
        token,
    }
}

/// Copies the repository's graph `rel` to `dest` with its `../assets/` paths made absolute,
/// so that it runs from any folder.
pub fn graph_copy(rel: &str, dest: &Path) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join(rel))
        .unwrap()
        .replace("../assets/", &format!("{}/", root.join("assets").display()));
    std::fs::write(dest, text).unwrap();
}

impl Browser {
    /// Sets the `input` element (a selector such as `input[type=range]`) of parameter
    /// `param` on node `node`'s card to `value` and fires its `change` event, as a user's
    /// edit does.
    pub fn set_widget(&mut self, node: &str, param: &str, input: &str, value: &str) {
        self.eval(&format!(
            "(() => {{ const i = document.querySelector('#node-{node} [data-param={param}] {input}');
                       i.value = {value}; i.dispatchEvent(new Event('change')); return true; }})()"
        ))
        .unwrap();
    }
}
