//! Shared by the fuzz targets: a per-process scratch folder for readers that take paths.

use std::path::PathBuf;

/// A scratch folder unique to this fuzzing process (readers that take a path read from it).
pub fn scratch() -> PathBuf {
    let base = std::env::var_os("CGNODES_FUZZ_TMP")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            if std::path::Path::new("/dev/shm").is_dir() {
                PathBuf::from("/dev/shm")
            } else {
                std::env::temp_dir()
            }
        });
    let d = base.join(format!("cgnodes-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("scratch folder");
    d
}
