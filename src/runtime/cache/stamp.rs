//! File stamps for cache keys: what identifies the content of a file a node reads without
//! reading large files whole, and the companion files some formats pull in (an OBJ's MTL
//! libraries and their texture maps).

use cgnodes_api::io::read_prefix;
use cgnodes_api::node::CompanionFn;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};
use std::time::UNIX_EPOCH;

/// Files up to this size are also hashed by content, so an edit that keeps the size and
/// lands within the file system's timestamp resolution (or a copy that keeps the time) is
/// still seen. Larger files are stamped by size and modification time only.
pub const CONTENT_HASH_MAX: u64 = 256 * 1024;

/// At most this many companion files are stamped per input file.
pub const MAX_COMPANIONS: usize = 256;

/// A file's size and modification time (nanoseconds since the epoch, 0 when unknown).
pub fn size_and_mtime(path: &Path) -> Option<(u64, u128)> {
    let m = std::fs::metadata(path).ok()?;
    let t = m
        .modified()
        .ok()
        .and_then(|t| t.duration_since(UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    Some((m.len(), t))
}

/// Adds one file to a key: its path, size, modification time and, when small, content hash;
/// a missing or unreadable file adds a marker instead.
pub fn stamp_file(h: &mut blake3::Hasher, path: &Path) {
    h.update(path.to_string_lossy().as_bytes());
    h.update(b"\0");
    match size_and_mtime(path) {
        Some((len, t)) => {
            h.update(&len.to_le_bytes());
            h.update(&t.to_le_bytes());
            if len <= CONTENT_HASH_MAX {
                if let Some(bytes) = read_prefix(path, CONTENT_HASH_MAX) {
                    h.update(blake3::hash(&bytes).as_bytes());
                }
            }
        }
        None => {
            h.update(b"<missing>");
        }
    }
}

/// Adds an input file and its companions (`companions(path)`, when the node declares them)
/// to a key.
pub fn stamp_input(h: &mut blake3::Hasher, path: &Path, companions: Option<CompanionFn>) {
    stamp_file(h, path);
    if let Some(f) = companions {
        for c in memo_companions(path, f).iter().take(MAX_COMPANIONS) {
            h.update(b"+");
            stamp_file(h, c);
        }
    }
}

type MemoKey = (PathBuf, usize, u64, u128);

/// The companions of `path`, remembered per file stamp: listing them reads the whole file
/// (an OBJ may be large), while stamping them is cheap.
fn memo_companions(path: &Path, f: CompanionFn) -> Vec<PathBuf> {
    static MEMO: OnceLock<Mutex<HashMap<MemoKey, Vec<PathBuf>>>> = OnceLock::new();
    let Some((len, t)) = size_and_mtime(path) else {
        return Vec::new();
    };
    // Small files are listed again each time: their stamp includes the content, so a memo
    // keyed by size and time could hide an edit that kept both.
    if len <= CONTENT_HASH_MAX {
        return f(path);
    }
    let key = (path.to_path_buf(), f as usize, len, t);
    let memo = MEMO.get_or_init(Mutex::default);
    if let Some(v) = memo.lock().unwrap_or_else(|p| p.into_inner()).get(&key) {
        return v.clone();
    }
    let v = f(path);
    memo.lock()
        .unwrap_or_else(|p| p.into_inner())
        .insert(key, v.clone());
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use cgnodes_formats::obj_companions::obj_companions;

    #[test]
    fn obj_companions_list_mtl_libraries_and_their_textures() {
        let d = tempfile::tempdir().unwrap();
        let obj = d.path().join("m.obj");
        std::fs::write(
            &obj,
            "mtllib a.mtl\n  mtllib  sub/b.mtl c.mtl\nmtllibx no\nv 0 0 0\n",
        )
        .unwrap();
        std::fs::write(
            d.path().join("a.mtl"),
            "newmtl x\nmap_Kd -s 1 1 1 tex/kd.png\n",
        )
        .unwrap();
        std::fs::create_dir(d.path().join("sub")).unwrap();
        std::fs::write(
            d.path().join("sub/b.mtl"),
            "newmtl y\nbump n.png\nKd 1 1 1\n",
        )
        .unwrap();
        let c = obj_companions(&obj);
        let rel: Vec<String> = c
            .iter()
            .map(|p| p.strip_prefix(d.path()).unwrap().display().to_string())
            .collect();
        assert_eq!(
            rel,
            [
                "a.mtl",
                "tex/kd.png",
                "sub/b.mtl c.mtl",
                "sub/b.mtl",
                "sub/n.png",
                "c.mtl"
            ]
        );
    }

    #[test]
    fn a_same_size_edit_within_the_same_second_changes_a_small_files_stamp() {
        let d = tempfile::tempdir().unwrap();
        let f = d.path().join("a.txt");
        let stamp = |p: &Path| {
            let mut h = blake3::Hasher::new();
            stamp_file(&mut h, p);
            h.finalize()
        };
        std::fs::write(&f, "one").unwrap();
        let t = std::fs::metadata(&f).unwrap().modified().unwrap();
        let s1 = stamp(&f);
        std::fs::write(&f, "two").unwrap();
        std::fs::File::options()
            .append(true)
            .open(&f)
            .unwrap()
            .set_modified(t)
            .unwrap();
        assert_ne!(s1, stamp(&f));
        assert_ne!(stamp(&f), stamp(&d.path().join("missing.txt")));
    }

    #[cfg(unix)]
    #[test]
    fn devices_are_stamped_without_being_read() {
        // /dev/zero has length 0 and never ends: reading it would hang the planner.
        let mut h = blake3::Hasher::new();
        stamp_input(&mut h, Path::new("/dev/zero"), Some(obj_companions));
        assert!(obj_companions(Path::new("/dev/zero")).is_empty());
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("m.obj"), "mtllib /dev/zero\n").unwrap();
        assert_eq!(obj_companions(&d.path().join("m.obj")).len(), 1);
        stamp_input(&mut h, &d.path().join("m.obj"), Some(obj_companions));
    }
}
