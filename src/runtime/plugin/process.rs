//! Runs a plugin process: request on stdin, response on stdout, log on stderr, with a time
//! limit. The process gets its own process group so that a timeout kills it together with
//! anything it started.

use std::io::{Read, Write};
use std::path::Path;
use std::process::{Child, Command, ExitStatus, Stdio};
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

/// Why a plugin process could not be run.
#[derive(Debug, thiserror::Error)]
pub enum ProcessError {
    #[error("the plugin command is empty")]
    EmptyCommand,
    /// The command did not start.
    #[error("cannot start {program}: {source}")]
    Start {
        program: String,
        source: std::io::Error,
    },
    /// Waiting for it failed (it was killed).
    #[error("waiting for the plugin failed: {0}")]
    Wait(std::io::Error),
}

/// Runs `argv` in `cwd` with `stdin` as input; kills it after `timeout`.
pub fn run(
    argv: &[std::ffi::OsString],
    cwd: &Path,
    env: &[(&str, &std::ffi::OsStr)],
    stdin: Vec<u8>,
    timeout: Duration,
) -> Result<Finished, ProcessError> {
    let t0 = Instant::now();
    // The group is registered so that Ctrl-C kills it (`io::interrupt`): it does not get the
    // terminal's SIGINT itself.
    let (_tracked, mut child) = spawn(argv, cwd, env)?;
    let spawn_ms = t0.elapsed().as_secs_f64() * 1e3;
    let rx = start_pipes(&mut child, stdin);
    let status = wait(&mut child, t0 + timeout)?;
    let run_ms = t0.elapsed().as_secs_f64() * 1e3;
    let (stdout, stderr) = collect(&rx, &mut child);
    Ok(Finished {
        status,
        stdout,
        stderr,
        spawn_ms,
        run_ms,
    })
}

/// Starts `argv` in `cwd` with piped stdio, in a process group of its own, registered so
/// that an interrupt kills the group.
fn spawn(
    argv: &[std::ffi::OsString],
    cwd: &Path,
    env: &[(&str, &std::ffi::OsStr)],
) -> Result<(cgnodes_api::io::interrupt::Tracked, Child), ProcessError> {
    let (prog, args) = argv.split_first().ok_or(ProcessError::EmptyCommand)?;
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
    cgnodes_api::io::interrupt::track(
        || cmd.spawn(),
        |c| cgnodes_api::io::interrupt::Resource::ProcessGroup(i32::try_from(c.id()).unwrap_or(0)),
    )
    .map_err(|source| ProcessError::Start {
        program: prog.to_string_lossy().into_owned(),
        source,
    })
}

/// Threads feeding `stdin` to the child and reading its stdout and (the tail of) its
/// stderr; each reader sends (is stdout, bytes) when its pipe closes.
fn start_pipes(child: &mut Child, stdin: Vec<u8>) -> mpsc::Receiver<(bool, Vec<u8>)> {
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
    if let Some(err) = child.stderr.take() {
        std::thread::spawn(move || {
            let _ = tx.send((false, read_tail(err)));
        });
    }
    rx
}

/// Reads a pipe to its end, keeping the last `STDERR_KEEP` bytes.
fn read_tail(mut pipe: impl Read) -> Vec<u8> {
    let mut buf = Vec::new();
    let mut chunk = [0u8; 8192];
    loop {
        let n = match pipe.read(&mut chunk) {
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
    buf
}

/// Waits for the child to exit, polling with a growing nap; kills its group at `deadline`
/// (`None`: killed).
fn wait(child: &mut Child, deadline: Instant) -> Result<Option<ExitStatus>, ProcessError> {
    let pid = child.id();
    let mut nap = Duration::from_micros(200);
    loop {
        match child.try_wait() {
            Ok(Some(s)) => return Ok(Some(s)),
            Ok(None) => {}
            Err(e) => {
                kill_group(pid, child);
                return Err(ProcessError::Wait(e));
            }
        }
        let now = Instant::now();
        if now >= deadline {
            kill_group(pid, child);
            let _ = child.wait();
            return Ok(None);
        }
        std::thread::sleep(nap.min(deadline - now));
        nap = (nap * 2).min(Duration::from_millis(10));
    }
}

/// Collects stdout and stderr; a process the plugin left behind may hold the pipes open, so
/// waits only briefly and then ends the whole group.
fn collect(rx: &mpsc::Receiver<(bool, Vec<u8>)>, child: &mut Child) -> (Vec<u8>, Vec<u8>) {
    let pid = child.id();
    let mut stdout = Vec::new();
    let mut stderr = Vec::new();
    let grace = Instant::now() + Duration::from_secs(2);
    for _ in 0..2 {
        let left = grace.saturating_duration_since(Instant::now());
        match rx.recv_timeout(left) {
            Ok((true, b)) => stdout = b,
            Ok((false, b)) => stderr = b,
            Err(_) => {
                kill_group(pid, child);
                break;
            }
        }
    }
    (stdout, stderr)
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
