//! Ctrl-C and SIGTERM: a registry of what must not outlive the process (plugin process
//! groups, temporary files and folders) and a handler that, on SIGINT or SIGTERM, kills the
//! groups, removes the temporaries and exits with code 130.
//!
//! Plugins run in their own process group (`plugin::process`), so the terminal's Ctrl-C does
//! not reach them; without this they kept running after `cgnodes` ended. The signal handler
//! does only async-signal-safe work: it writes the signal number to a pipe (the self-pipe
//! trick, D. J. Bernstein), and a watcher thread reading the pipe does the cleanup.

use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};

/// Something to clean up when the process is interrupted.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Resource {
    /// A process group, by its id (the pid of its leader): killed with SIGKILL.
    ProcessGroup(i32),
    /// A temporary file or folder: removed.
    Path(PathBuf),
}

/// What is live now. Held locked by the watcher from the cleanup until the exit, so nothing
/// is created and left behind meanwhile.
static LIVE: Mutex<BTreeSet<Resource>> = Mutex::new(BTreeSet::new());

fn live() -> MutexGuard<'static, BTreeSet<Resource>> {
    LIVE.lock().unwrap_or_else(|p| p.into_inner())
}

/// Keeps a resource registered; dropping it unregisters the resource (it was cleaned up, or
/// became permanent, in the normal way).
#[must_use = "the resource is unregistered when this is dropped"]
#[derive(Debug)]
pub struct Tracked(Resource);

impl Drop for Tracked {
    fn drop(&mut self) {
        live().remove(&self.0);
    }
}

/// Creates something with `create` and registers the resource `what` names, with the
/// registry locked in between: an interrupt cannot fall between the creation and the
/// registration. Returns the guard first, so that `let (_guard, x) = track(..)` drops `x`
/// (removing the temporary) before the guard.
pub fn track<T, E>(
    create: impl FnOnce() -> Result<T, E>,
    what: impl FnOnce(&T) -> Resource,
) -> Result<(Tracked, T), E> {
    let mut l = live();
    let t = create()?;
    let r = what(&t);
    l.insert(r.clone());
    Ok((Tracked(r), t))
}

/// Installs the SIGINT and SIGTERM handlers (once; later calls do nothing). Only the
/// command line calls this: a program using the library keeps its own signal handling.
pub fn install() {
    #[cfg(unix)]
    unix::install();
}

/// Kills every registered process group, removes every registered temporary and exits
/// with code 130. The registry stays locked until the exit.
fn clean_up_and_exit() -> ! {
    let l = live();
    for r in l.iter() {
        match r {
            #[cfg(unix)]
            Resource::ProcessGroup(g) => {
                // SAFETY: kill(2) with a negative pid signals the group `g` leads; it touches
                // no memory.
                unsafe {
                    libc::kill(-g, libc::SIGKILL);
                }
            }
            #[cfg(not(unix))]
            Resource::ProcessGroup(_) => {}
            Resource::Path(p) => {
                let _ = if p.is_dir() {
                    std::fs::remove_dir_all(p)
                } else {
                    std::fs::remove_file(p)
                };
            }
        }
    }
    eprintln!("interrupted");
    std::process::exit(130)
}

#[cfg(unix)]
mod unix {
    use std::sync::atomic::{AtomicI32, Ordering};

    /// The pipe's write end, for the handler (-1 before `install`).
    static WRITE_FD: AtomicI32 = AtomicI32::new(-1);

    /// The signal handler: writes one byte to the pipe and restores `errno`. write(2) is
    /// async-signal-safe; nothing here allocates or locks.
    extern "C" fn on_signal(sig: libc::c_int) {
        let saved = errno();
        let fd = WRITE_FD.load(Ordering::Relaxed);
        let b = sig as u8;
        // SAFETY: writes one byte from a live stack variable to a pipe we own.
        unsafe {
            libc::write(fd, (&b as *const u8).cast(), 1);
        }
        set_errno(saved);
    }

    /// The calling thread's `errno` location, where libc exposes it.
    #[cfg(any(target_os = "linux", target_os = "android"))]
    fn errno_ptr() -> Option<*mut libc::c_int> {
        // SAFETY: returns the calling thread's errno location.
        Some(unsafe { libc::__errno_location() })
    }
    #[cfg(any(target_os = "macos", target_os = "ios", target_os = "freebsd"))]
    fn errno_ptr() -> Option<*mut libc::c_int> {
        // SAFETY: returns the calling thread's errno location.
        Some(unsafe { libc::__error() })
    }
    #[cfg(not(any(
        target_os = "linux",
        target_os = "android",
        target_os = "macos",
        target_os = "ios",
        target_os = "freebsd"
    )))]
    fn errno_ptr() -> Option<*mut libc::c_int> {
        None
    }

    fn errno() -> libc::c_int {
        // SAFETY: the pointer is the thread's own errno.
        errno_ptr().map_or(0, |p| unsafe { *p })
    }

    fn set_errno(v: libc::c_int) {
        if let Some(p) = errno_ptr() {
            // SAFETY: the pointer is the thread's own errno.
            unsafe { *p = v }
        }
    }

    pub(super) fn install() {
        static ONCE: std::sync::Once = std::sync::Once::new();
        ONCE.call_once(|| {
            let mut fds = [0 as libc::c_int; 2];
            // SAFETY: pipe(2) fills the two-element array; fcntl(2) on the fds it returned.
            unsafe {
                if libc::pipe(fds.as_mut_ptr()) != 0 {
                    return;
                }
                for fd in fds {
                    libc::fcntl(fd, libc::F_SETFD, libc::FD_CLOEXEC);
                }
                // A full pipe must not block the handler: one byte is enough to wake the
                // watcher.
                libc::fcntl(fds[1], libc::F_SETFL, libc::O_NONBLOCK);
            }
            WRITE_FD.store(fds[1], Ordering::Relaxed);
            let read_fd = fds[0];
            let watcher = std::thread::Builder::new()
                .name("cgnodes-signals".into())
                .spawn(move || loop {
                    let mut b = 0u8;
                    // SAFETY: reads one byte into a live stack variable from our pipe.
                    let n = unsafe { libc::read(read_fd, (&mut b as *mut u8).cast(), 1) };
                    if n == 1 {
                        super::clean_up_and_exit();
                    }
                    if n < 0
                        && std::io::Error::last_os_error().kind() == std::io::ErrorKind::Interrupted
                    {
                        continue;
                    }
                    return;
                });
            if watcher.is_err() {
                return;
            }
            for sig in [libc::SIGINT, libc::SIGTERM] {
                // SAFETY: a zeroed sigaction is valid; the handler is an extern "C" fn that
                // does only async-signal-safe work.
                unsafe {
                    let mut sa: libc::sigaction = std::mem::zeroed();
                    sa.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as usize;
                    sa.sa_flags = libc::SA_RESTART;
                    libc::sigemptyset(&mut sa.sa_mask);
                    libc::sigaction(sig, &sa, std::ptr::null_mut());
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tracked_resources_are_registered_until_dropped() {
        let p = PathBuf::from("/nonexistent/cgnodes-interrupt-test");
        let (g, v) = track(|| Ok::<_, ()>(7), |_| Resource::Path(p.clone())).unwrap();
        assert_eq!(v, 7);
        assert!(live().contains(&Resource::Path(p.clone())));
        drop(g);
        assert!(!live().contains(&Resource::Path(p.clone())));
        // A failed creation registers nothing.
        let r = track(|| Err::<u8, _>("no"), |_| Resource::Path(p.clone()));
        assert!(r.is_err());
        assert!(!live().contains(&Resource::Path(p)));
    }
}
