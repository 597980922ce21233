//! Result caches. The memory cache serves repeated runs in one process (frames, sweeps); the
//! disk cache (`--cache DIR`) is content-addressed by the same keys, so a re-run in another
//! process recomputes only what changed.
//!
//! # What a key covers
//! A node's key (BLAKE3) hashes:
//! - the build identity (`build_identity`): the crate version, the key/entry format
//!   (`FORMAT`) and the size and modification time of the running executable. The version
//!   alone would let a rebuilt development binary or a locally patched release serve results
//!   of the old code; the executable's stamp changes with every build, so a rebuilt or
//!   upgraded cgnodes starts a fresh key space (a rebuild that changed nothing misses once).
//!   Nodes compiled into the executable (built-in or linked crates) are covered by it;
//!   plugin nodes carry a stamp of their folder in their `source` (see `plugin::load`).
//! - the node's type and source, its literal inputs, and the keys of the nodes it reads from
//!   (so unchanged subgraphs keep their keys);
//! - every file it reads (`stamp::stamp_input`): the resolved path, size, modification time
//!   and, for files up to `stamp::CONTENT_HASH_MAX`, a hash of the content; plus the files
//!   its declaration names as companions of an input file (`NodeDecl::companions`: an OBJ's
//!   MTL libraries and their texture maps for `scene_load`). A path given as a literal is
//!   stamped when the run is planned; a path that arrives through a link is stamped when the
//!   linked value arrives, before the cache lookup, and the changed key then propagates to
//!   every node downstream;
//! - the frame, for nodes that depend on time;
//! - for stateful nodes (simulations), their history: the key at frame f hashes the key
//!   the same node had at the frame that last advanced the state it holds, or marks the
//!   origin when it holds no state (first frame of a process, after `reset_states`, or after
//!   the node dropped its state). A key thus chains every frame's inputs back to where the
//!   state started, and a downstream result is served only when the simulation followed
//!   the same history: `--frames 0..20` then `--frames 10..12` in a new process computes
//!   frame 10 from the node's initial state and does not serve the frame 10 of the first run.
//!   Stateful nodes themselves always run (their state must advance).
//! - for writers, the output folder.
//!
//! # The disk cache
//! One file per key (`DIR/ab/abcd....bin`), starting with a header (magic, `FORMAT`, the
//! build identity, the key): an entry written by another version or build is a miss, never
//! decoded as data of another layout. A hit touches the file's modification time, which
//! orders entries by last use; `DiskCache::evict` removes the least recently used entries
//! until the folder is under a size limit (`cgnodes run --cache-size`, default 1 GiB).

mod disk;
pub mod stamp;

pub use cgnodes_api::node::CompanionFn;
pub use disk::{DiskCache, Evicted};
pub use stamp::stamp_input;

use cgnodes_api::types::Value;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

/// Version of the key derivation and of the disk entry layout; bump it when either changes
/// (or when a change of the runtime must not serve older results).
pub const FORMAT: u32 = 2;

/// The identity of this build, mixed into every key and written in every disk entry: the
/// crate version, `FORMAT`, and the size and modification time of the running executable
/// (when it can be read).
pub fn build_identity() -> Key {
    static ID: OnceLock<Key> = OnceLock::new();
    *ID.get_or_init(|| {
        let mut h = blake3::Hasher::new();
        h.update(b"cgnodes\0");
        h.update(env!("CARGO_PKG_VERSION").as_bytes());
        h.update(b"\0");
        h.update(&FORMAT.to_le_bytes());
        if let Some((len, t)) = std::env::current_exe()
            .ok()
            .and_then(|p| stamp::size_and_mtime(&p))
        {
            h.update(&len.to_le_bytes());
            h.update(&t.to_le_bytes());
        }
        *h.finalize().as_bytes()
    })
}

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
