//! File watching for `run --watch` and `serve`: the graph file and the files it reads, watched
//! through the OS's change events (`notify`: inotify on Linux) instead of polling. Folders
//! are watched, not files, because editors save by writing a new file and renaming it over
//! the old one, which ends a watch on the file itself.

use notify::{EventKind, RecommendedWatcher, RecursiveMode, Watcher};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::mpsc::Receiver;
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// How long the files must stay quiet before a change counts: an editor's save is often
/// several events (write, rename, attribute change) within a few milliseconds.
pub const DEBOUNCE: Duration = Duration::from_millis(60);

/// Watches a set of files (and folders, for `{frame}` patterns) and calls back on a change.
pub struct FileWatch {
    watcher: RecommendedWatcher,
    /// The folders watched.
    dirs: BTreeSet<PathBuf>,
    /// The files (or folders) whose changes count, as absolute paths.
    wanted: Arc<Mutex<BTreeSet<PathBuf>>>,
}

/// `path` made absolute with its folder's symbolic links and `..` resolved (the form the
/// OS's events name it by); as given when the folder does not exist.
pub fn normalize(path: &Path) -> PathBuf {
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    match (abs.parent(), abs.file_name()) {
        (Some(dir), Some(name)) => match dir.canonicalize() {
            Ok(d) => d.join(name),
            Err(_) => abs.clone(),
        },
        _ => abs.clone(),
    }
}

/// The system's file watcher could not be started.
#[derive(Debug, thiserror::Error)]
#[error("cannot watch files: {0}")]
pub struct WatchError(notify::Error);

impl FileWatch {
    /// A watch that calls `on_change(path)` from the watcher's thread for every change to a
    /// wanted path (nothing is wanted until `set`).
    pub fn new(on_change: impl Fn(PathBuf) + Send + 'static) -> Result<FileWatch, WatchError> {
        let wanted: Arc<Mutex<BTreeSet<PathBuf>>> = Arc::default();
        let w = wanted.clone();
        let watcher = notify::recommended_watcher(move |ev: notify::Result<notify::Event>| {
            let Ok(ev) = ev else {
                return;
            };
            if matches!(ev.kind, EventKind::Access(_)) {
                return;
            }
            let wanted = w.lock().unwrap_or_else(|e| e.into_inner());
            for p in ev.paths {
                let hit = wanted.contains(&p) || p.parent().is_some_and(|d| wanted.contains(d));
                if hit {
                    on_change(p);
                }
            }
        })
        .map_err(WatchError)?;
        Ok(FileWatch {
            watcher,
            dirs: BTreeSet::new(),
            wanted,
        })
    }

    /// Watches exactly `paths` from now on (files, or folders whose direct entries count).
    pub fn set(&mut self, paths: &[PathBuf]) {
        let wanted: BTreeSet<PathBuf> = paths.iter().map(|p| normalize(p)).collect();
        let dirs: BTreeSet<PathBuf> = wanted
            .iter()
            .filter_map(|p| {
                if p.is_dir() {
                    Some(p.clone())
                } else {
                    p.parent().map(Path::to_path_buf)
                }
            })
            .filter(|d| d.is_dir())
            .collect();
        for d in self.dirs.difference(&dirs) {
            let _ = self.watcher.unwatch(d);
        }
        for d in dirs.difference(&self.dirs) {
            if let Err(e) = self.watcher.watch(d, RecursiveMode::NonRecursive) {
                eprintln!("warning: cannot watch {}: {e}", d.display());
            }
        }
        self.dirs = dirs;
        *self.wanted.lock().unwrap_or_else(|e| e.into_inner()) = wanted;
    }
}

/// Blocks until a change arrives on `rx`, then until `DEBOUNCE` passes without another;
/// returns the paths changed (none when the sender is gone).
pub fn wait_quiet(rx: &Receiver<PathBuf>) -> Vec<PathBuf> {
    let Ok(first) = rx.recv() else {
        return Vec::new();
    };
    let mut changed = BTreeSet::from([first]);
    while let Ok(p) = rx.recv_timeout(DEBOUNCE) {
        changed.insert(p);
    }
    changed.into_iter().collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::mpsc::channel;

    #[test]
    fn a_saved_file_is_reported_once_quiet_and_others_are_not() {
        let dir = tempfile::tempdir().unwrap();
        let graph = dir.path().join("g.json");
        let other = dir.path().join("other.txt");
        std::fs::write(&graph, "{}").unwrap();
        let (tx, rx) = channel();
        let mut w = FileWatch::new(move |p| {
            let _ = tx.send(p);
        })
        .unwrap();
        w.set(std::slice::from_ref(&graph));
        std::fs::write(&other, "x").unwrap();
        // An editor's save: a new file renamed over the old one.
        let tmp = dir.path().join(".g.json.tmp");
        std::fs::write(&tmp, "{\"a\": 1}").unwrap();
        std::fs::rename(&tmp, &graph).unwrap();
        let changed = wait_quiet(&rx);
        assert_eq!(changed, vec![normalize(&graph)]);
        // Nothing else is pending after the quiet period.
        assert!(rx.recv_timeout(Duration::from_millis(100)).is_err());
    }
}
