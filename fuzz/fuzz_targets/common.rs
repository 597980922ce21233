//! Shared by the fuzz targets: a per-process scratch folder for readers that take paths.

use std::path::PathBuf;

/// A scratch folder unique to this fuzzing process (in /dev/shm when there is one).
pub fn scratch() -> &'static std::path::Path {
    static DIR: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    DIR.get_or_init(make)
}

fn make() -> PathBuf {
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
