//! Result caches. A node's key hashes its type, its literal inputs, the keys of the nodes it
//! reads from (so unchanged subgraphs keep their keys), the stamp of any file it reads, and
//! the frame when it depends on time (as Graphite and ComfyUI do). The memory cache serves
//! repeated runs in one process (frames, sweeps); the disk cache (`--cache DIR`) is
//! content-addressed by the same keys, so a re-run recomputes only what changed.

use crate::types::Value;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A cache key (BLAKE3 of the node's definition and its inputs' keys).
pub type Key = [u8; 32];

/// Hex text of a key.
pub fn hex(k: &Key) -> String {
    k.iter().map(|b| format!("{b:02x}")).collect()
}

/// A node's cached result: its outputs, the outputs it skipped because no one wanted them,
/// and the files it wrote.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Entry {
    /// Output values by socket.
    pub outputs: Arc<BTreeMap<String, Value>>,
    /// Files the node wrote (a hit needs them all still present).
    pub written: Vec<PathBuf>,
    /// Declared outputs the node did not produce because they were not wanted; a run that
    /// wants one of them cannot be served from this entry.
    pub skipped: Vec<String>,
}

impl Entry {
    /// Whether every file the node wrote is still there.
    pub fn files_present(&self) -> bool {
        self.written.iter().all(|p| p.exists())
    }

    /// Whether this entry holds every output in `wanted` (`None` = every output).
    pub fn serves(&self, wanted: Option<&BTreeSet<String>>) -> bool {
        match wanted {
            None => self.skipped.is_empty(),
            Some(w) => !self.skipped.iter().any(|s| w.contains(s)),
        }
    }

    /// This fresh entry completed with the outputs of an older entry of the same key (same
    /// inputs, so the same values): an output skipped now but produced before is kept.
    pub fn merged_with(self, older: &Entry) -> Entry {
        let mut outputs = (*older.outputs).clone();
        outputs.extend(self.outputs.iter().map(|(k, v)| (k.clone(), v.clone())));
        let mut skipped = self.skipped;
        skipped.retain(|s| !outputs.contains_key(s));
        let mut written = self.written;
        for w in &older.written {
            if !written.contains(w) {
                written.push(w.clone());
            }
        }
        Entry {
            outputs: Arc::new(outputs),
            written,
            skipped,
        }
    }
}

/// In-memory cache that keeps what the current and the previous run used.
#[derive(Default)]
pub struct MemoryCache {
    entries: HashMap<Key, (u64, Entry)>,
    generation: u64,
}

impl MemoryCache {
    /// Starts a new run: entries not used in the last two runs are dropped.
    pub fn next_generation(&mut self) {
        self.generation += 1;
        let g = self.generation;
        self.entries.retain(|_, (used, _)| *used + 2 > g);
    }
    /// Looks up a key and marks it used.
    pub fn get(&mut self, k: &Key) -> Option<Entry> {
        let g = self.generation;
        self.entries.get_mut(k).map(|(used, e)| {
            *used = g;
            e.clone()
        })
    }
    /// Stores an entry.
    pub fn put(&mut self, k: Key, e: Entry) {
        self.entries.insert(k, (self.generation, e));
    }
    /// Number of entries.
    pub fn len(&self) -> usize {
        self.entries.len()
    }
    /// Whether the cache is empty.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

/// Content-addressed cache on disk: one file per key.
pub struct DiskCache {
    dir: PathBuf,
}

impl DiskCache {
    /// A cache in `dir` (created if missing).
    pub fn open(dir: &Path) -> std::io::Result<DiskCache> {
        std::fs::create_dir_all(dir)?;
        Ok(DiskCache {
            dir: dir.to_path_buf(),
        })
    }
    fn path(&self, k: &Key) -> PathBuf {
        let h = hex(k);
        self.dir.join(&h[..2]).join(format!("{h}.bin"))
    }
    /// Reads an entry; unreadable or stale files count as misses.
    pub fn get(&self, k: &Key) -> Option<Entry> {
        let bytes = std::fs::read(self.path(k)).ok()?;
        postcard::from_bytes(&bytes).ok()
    }
    /// Writes an entry atomically; failures are ignored (a cache is an optimisation).
    pub fn put(&self, k: &Key, e: &Entry) {
        if let Ok(bytes) = postcard::to_stdvec(e) {
            let _ = crate::io::write_atomic(&self.path(k), |w| w.write_all(&bytes));
        }
    }
}
