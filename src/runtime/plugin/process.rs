//! Runs a plugin process: request on stdin, response on stdout, log on stderr, with a time
//! limit. The process gets its own process group so that a timeout kills it together with
//! anything it started.

use std::io::{Read, Write};
use std::path::Path;
use std::process::{Command, ExitStatus, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// At most this much of stderr is kept (the tail).
const STDERR_KEEP: usize = 64 * 1024;

/// How a plugin process ended.
#[derive(Debug)]
pub struct Finished {
    /// Exit status (`None` when it was killed for running too long).
    pub status: Option<ExitStatus>,
    /// Everything it wrote to stdout.
    pub stdout: Vec<u8>,
    /// The tail of what it wrote to stderr.
    pub stderr: Vec<u8>,
    /// Milliseconds spent starting the process.
    pub spawn_ms: f64,
    /// Milliseconds from start to exit.
    pub run_ms: f64,
}

/// Runs `argv` in `cwd` with `stdin` as input; kills it after `timeout`.
pub fn run(
    argv: &[std::ffi::OsString],
    cwd: &Path,
    env: &[(&str, &std::ffi::OsStr)],
    stdin: Vec<u8>,
    timeout: Duration,
) -> Result<Finished, String> {
    let (prog, args) = argv.split_first().ok_or("the plugin command is empty")?;
    let mut cmd = Command::new(prog);
    cmd.args(args)
        .current_dir(cwd)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    for (k, v) in env {
        cmd.env(k, v);
    }
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        cmd.process_group(0);
    }
    let t0 = Instant::now();
    // The group is registered so that Ctrl-C kills it (`io::interrupt`): it does not get the
    // terminal's SIGINT itself.
    let (_tracked, mut child) = cgnodes_api::io::interrupt::track(
        || cmd.spawn(),
        |c| cgnodes_api::io::interrupt::Resource::ProcessGroup(i32::try_from(c.id()).unwrap_or(0)),
    )
    .map_err(|e| format!("cannot start {}: {e}", prog.to_string_lossy()))?;
    let spawn_ms = t0.elapsed().as_secs_f64() * 1e3;
    let pid = child.id();
    let (tx, rx) = mpsc::channel::<(bool, Vec<u8>)>();
    if let Some(mut input) = child.stdin.take() {
        // A plugin that exits without reading its input is not an error here; its exit
        // status and response say what happened.
        std::thread::spawn(move || {
            let _ = input.write_all(&stdin);
        });
    }
    if let Some(mut out) = child.stdout.take() {
        let tx = tx.clone();
        std::thread::spawn(move || {
            let mut buf = Vec::new();
            let _ = out.read_to_end(&mut buf);
            let _ = tx.send((true, buf));
        });
    }
    if let Some(mut err) = child.stderr.take() {
        let tx = tx.clone();
        std::thread::spawn(move || {
            let mut buf = Vec::new();
            let mut chunk = [0u8; 8192];
            loop {
                let n = match err.read(&mut chunk) {
                    Ok(0) => break,
                    Ok(n) => n,
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                    Err(_) => break,
                };
                buf.extend_from_slice(&chunk[..n]);
                if buf.len() > 2 * STDERR_KEEP {
                    buf.drain(..buf.len() - STDERR_KEEP);
                }
            }
            if buf.len() > STDERR_KEEP {
                buf.drain(..buf.len() - STDERR_KEEP);
            }
            let _ = tx.send((false, buf));
        });
    }
    drop(tx);
    let deadline = t0 + timeout;
    let mut nap = Duration::from_micros(200);
    let status = loop {
        match child.try_wait() {
            Ok(Some(s)) => break Some(s),
            Ok(None) => {}
            Err(e) => {
                kill_group(pid, &mut child);
                return Err(format!("waiting for the plugin failed: {e}"));
            }
        }
        let now = Instant::now();
        if now >= deadline {
            kill_group(pid, &mut child);
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(nap.min(deadline - now));
        nap = (nap * 2).min(Duration::from_millis(10));
    };
    let run_ms = t0.elapsed().as_secs_f64() * 1e3;
    // Collect the pipes; a process the plugin left behind may hold them open, so wait only
    // briefly and then end the whole group.
    let mut stdout = Vec::new();
    let mut stderr = Vec::new();
    let grace = Instant::now() + Duration::from_secs(2);
    for _ in 0..2 {
        let left = grace.saturating_duration_since(Instant::now());
        match rx.recv_timeout(left) {
            Ok((true, b)) => stdout = b,
            Ok((false, b)) => stderr = b,
            Err(_) => {
                kill_group(pid, &mut child);
                break;
            }
        }
    }
    Ok(Finished {
        status,
        stdout,
        stderr,
        spawn_ms,
        run_ms,
    })
}

/// Kills the plugin's process group (the plugin and anything it started).
fn kill_group(pid: u32, child: &mut std::process::Child) {
    #[cfg(unix)]
    {
        if let Ok(pgid) = i32::try_from(pid) {
            // SAFETY: kill(2) with a negative pid signals the process group the plugin leads
            // (it was started with process_group(0)); it touches no memory.
            unsafe {
                libc::kill(-pgid, libc::SIGKILL);
            }
        }
    }
    let _ = child.kill();
}
