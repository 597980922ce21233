//! The disk cache: one file per key, each starting with a header that names the build that
//! wrote it, touched on every hit so that eviction can remove the least recently used.

use super::{build_identity, hex, Entry, Key, FORMAT};
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// First bytes of every entry file.
const MAGIC: &[u8; 8] = b"CGNCACHE";
/// Header length: magic, format, build identity, key.
const HEADER: usize = 8 + 4 + 32 + 32;

/// Content-addressed cache on disk: one file per key.
pub struct DiskCache {
    dir: PathBuf,
    identity: Key,
}

/// What `DiskCache::evict` did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Evicted {
    /// Entries removed.
    pub removed: usize,
    /// Bytes freed.
    pub freed: u64,
    /// Bytes the remaining entries take.
    pub kept: u64,
}

impl DiskCache {
    /// A cache in `dir` (created if missing) for this build (`build_identity`).
    pub fn open(dir: &Path) -> std::io::Result<DiskCache> {
        DiskCache::with_identity(dir, build_identity())
    }

    /// A cache in `dir` that reads and writes entries as the build `identity` would (tests
    /// use it to play another version).
    pub fn with_identity(dir: &Path, identity: Key) -> std::io::Result<DiskCache> {
        std::fs::create_dir_all(dir)?;
        Ok(DiskCache {
            dir: dir.to_path_buf(),
            identity,
        })
    }

    /// The file that holds the entry of `k`.
    pub fn path(&self, k: &Key) -> PathBuf {
        let h = hex(k);
        self.dir.join(&h[..2]).join(format!("{h}.bin"))
    }

    fn header(&self, k: &Key) -> [u8; HEADER] {
        let mut h = [0u8; HEADER];
        h[..8].copy_from_slice(MAGIC);
        h[8..12].copy_from_slice(&FORMAT.to_le_bytes());
        h[12..44].copy_from_slice(&self.identity);
        h[44..].copy_from_slice(k);
        h
    }

    /// Reads an entry and marks it used (its modification time becomes now). Unreadable
    /// files, files written by another format or build, and files of another key are misses.
    pub fn get(&self, k: &Key) -> Option<Entry> {
        let path = self.path(k);
        let bytes = std::fs::read(&path).ok()?;
        if bytes.len() < HEADER || bytes[..HEADER] != self.header(k) {
            return None;
        }
        let e = postcard::from_bytes(&bytes[HEADER..]).ok()?;
        touch(&path);
        Some(e)
    }

    /// Writes an entry atomically; failures are ignored (a cache is an optimisation).
    pub fn put(&self, k: &Key, e: &Entry) {
        if let Ok(bytes) = postcard::to_stdvec(e) {
            let head = self.header(k);
            let _ = cgnodes_api::io::write_atomic(&self.path(k), |w| {
                w.write_all(&head)?;
                w.write_all(&bytes)
            });
        }
    }

    /// Removes the least recently used entries (oldest modification time first) until the
    /// entries take at most `limit` bytes; `limit` 0 means no limit. Sizes are file lengths.
    /// Temporary files of interrupted writes older than an hour are removed too; other files
    /// that are not entries (`ab/<64 hex digits>.bin`) are left alone.
    pub fn evict(&self, limit: u64) -> Evicted {
        let mut files = self.entries();
        let total: u64 = files.iter().map(|f| f.1).sum();
        let mut ev = Evicted {
            kept: total,
            ..Evicted::default()
        };
        if limit == 0 || total <= limit {
            return ev;
        }
        files.sort();
        for (_, len, path) in files {
            if ev.kept <= limit {
                break;
            }
            if std::fs::remove_file(&path).is_ok() {
                ev.removed += 1;
                ev.freed += len;
                ev.kept -= len;
            }
        }
        ev
    }

    /// Every entry file with its last use and length.
    fn entries(&self) -> Vec<(SystemTime, u64, PathBuf)> {
        let mut v = Vec::new();
        let Ok(top) = std::fs::read_dir(&self.dir) else {
            return v;
        };
        for sub in top.filter_map(|e| e.ok()) {
            let name = sub.file_name();
            let name = name.to_string_lossy();
            if name.len() != 2 || !name.bytes().all(|b| b.is_ascii_hexdigit()) {
                continue;
            }
            let Ok(rd) = std::fs::read_dir(sub.path()) else {
                continue;
            };
            for f in rd.filter_map(|e| e.ok()) {
                let fname = f.file_name();
                let is_entry = fname.to_str().is_some_and(|n| {
                    n.len() == 68
                        && n.ends_with(".bin")
                        && n[..64].bytes().all(|b| b.is_ascii_hexdigit())
                });
                let Ok(m) = f.metadata() else { continue };
                let stale_tmp = fname
                    .to_str()
                    .is_some_and(|n| n.starts_with(".cgnodes-") && n.ends_with(".tmp"))
                    && m.modified()
                        .ok()
                        .and_then(|t| t.elapsed().ok())
                        .is_some_and(|age| age.as_secs() > 3600);
                if stale_tmp {
                    let _ = std::fs::remove_file(f.path());
                } else if is_entry && m.is_file() {
                    let t = m.modified().unwrap_or(SystemTime::UNIX_EPOCH);
                    v.push((t, m.len(), f.path()));
                }
            }
        }
        v
    }
}

/// Sets a file's modification time to now (its last use); failures are ignored.
fn touch(path: &Path) {
    if let Ok(f) = std::fs::OpenOptions::new().append(true).open(path) {
        let _ = f.set_modified(SystemTime::now());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;
    use std::sync::Arc;
    use std::time::Duration;

    fn entry(x: f64) -> Entry {
        let mut o = BTreeMap::new();
        o.insert("value".to_string(), cgnodes_api::types::Value::Float(x));
        Entry {
            outputs: Arc::new(o),
            written: Vec::new(),
            skipped: Vec::new(),
        }
    }

    fn value(e: &Entry) -> f64 {
        match e.outputs.get("value") {
            Some(cgnodes_api::types::Value::Float(x)) => *x,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn an_entry_written_by_another_version_is_a_miss() {
        let d = tempfile::tempdir().unwrap();
        let k = [7u8; 32];
        let old = DiskCache::with_identity(d.path(), [1u8; 32]).unwrap();
        old.put(&k, &entry(1.0));
        assert_eq!(value(&old.get(&k).unwrap()), 1.0);
        // The same key (a collision, or a copied folder) under another build: a miss.
        let new = DiskCache::with_identity(d.path(), [2u8; 32]).unwrap();
        assert!(new.get(&k).is_none());
        // A file of the format before headers (bare postcard) is a miss, not a decode.
        let bare = postcard::to_stdvec(&entry(3.0)).unwrap();
        std::fs::write(new.path(&k), bare).unwrap();
        assert!(new.get(&k).is_none());
        // A file renamed to another key is a miss.
        new.put(&k, &entry(4.0));
        let k2 = [8u8; 32];
        std::fs::create_dir_all(new.path(&k2).parent().unwrap()).unwrap();
        std::fs::copy(new.path(&k), new.path(&k2)).unwrap();
        assert!(new.get(&k2).is_none());
        assert_eq!(value(&new.get(&k).unwrap()), 4.0);
    }

    #[test]
    fn eviction_removes_the_least_recently_used_entries() {
        let d = tempfile::tempdir().unwrap();
        let c = DiskCache::open(d.path()).unwrap();
        let keys: Vec<Key> = (0..4u8).map(|i| [i; 32]).collect();
        let t0 = SystemTime::now() - Duration::from_secs(3600);
        for (i, k) in keys.iter().enumerate() {
            c.put(k, &entry(i as f64));
            let f = std::fs::OpenOptions::new()
                .append(true)
                .open(c.path(k))
                .unwrap();
            f.set_modified(t0 + Duration::from_secs(i as u64)).unwrap();
        }
        // A hit makes entry 0 the most recently used.
        assert_eq!(value(&c.get(&keys[0]).unwrap()), 0.0);
        let size = std::fs::metadata(c.path(&keys[0])).unwrap().len();
        // A stray file that is no entry is neither counted nor removed; a temporary file of
        // a write interrupted long ago is removed.
        std::fs::write(d.path().join("notes.txt"), "keep").unwrap();
        let tmp = c.path(&keys[0]).with_file_name(".cgnodes-x.tmp");
        std::fs::write(&tmp, "partial").unwrap();
        let f = std::fs::OpenOptions::new().append(true).open(&tmp).unwrap();
        f.set_modified(t0 - Duration::from_secs(60)).unwrap();
        assert_eq!(c.evict(0).removed, 0, "0 means no limit");
        let ev = c.evict(2 * size);
        assert_eq!((ev.removed, ev.kept), (2, 2 * size), "{ev:?}");
        // Entries 1 and 2 were the least recently used.
        assert!(!c.path(&keys[1]).exists() && !c.path(&keys[2]).exists());
        assert_eq!(value(&c.get(&keys[3]).unwrap()), 3.0);
        assert_eq!(value(&c.get(&keys[0]).unwrap()), 0.0);
        assert!(d.path().join("notes.txt").exists());
        assert!(!tmp.exists());
        // Under the limit: nothing more goes.
        assert_eq!(c.evict(2 * size).removed, 0);
    }
}
