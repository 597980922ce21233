//! File helpers shared by the runtime and the writer nodes: atomic writes, CSV (`csv`), and
//! the cleanup of temporaries and plugin processes on Ctrl-C (`interrupt`), and provenance
//! records inside written files (`provenance`).

pub mod csv;
pub mod interrupt;
pub mod json;
pub mod provenance;

use std::io::{BufWriter, Write};
use std::path::Path;

/// Writes `path` atomically: the data goes to a temporary file in the same folder, which is
/// renamed over `path` only when `f` succeeds. A failure leaves no partial file.
pub fn write_atomic(
    path: &Path,
    f: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir)?;
    // Registered so that Ctrl-C removes it (`interrupt`).
    let (_tracked, tmp) = interrupt::track(
        || {
            tempfile::Builder::new()
                .prefix(".cgnodes-")
                .suffix(".tmp")
                .tempfile_in(&dir)
        },
        |t| interrupt::Resource::Path(t.path().to_path_buf()),
    )?;
    {
        let mut w = BufWriter::new(tmp.as_file());
        f(&mut w)?;
        w.flush()?;
    }
    // Temporary files are private (0600); the result should read like any other file.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))?;
    }
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// Whether `path` is a regular file (not a folder, device or FIFO, which are never read:
/// `/dev/zero` never ends and opening a FIFO blocks).
pub fn is_regular_file(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| m.is_file())
}

/// Reads at most `max` + 1 bytes of a regular file (`None` for anything else or on error).
pub fn read_prefix(path: &Path, max: u64) -> Option<Vec<u8>> {
    use std::io::Read;
    if !is_regular_file(path) {
        return None;
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .ok()?
        .take(max + 1)
        .read_to_end(&mut bytes)
        .ok()?;
    Some(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_nothing() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("x.txt");
        let r = write_atomic(&p, |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("boom"))
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 0);
        write_atomic(&p, |w| w.write_all(b"ok")).unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "ok");
    }
}
