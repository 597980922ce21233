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

const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Registers the shipped DejaVu Sans as plotters' "sans-serif" (once), so charts and the
/// `plot` node draw text without depending on the system's fonts.
pub fn register_plot_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // The font is shipped with the crate, so this cannot fail for a valid build.
        let _ =
            plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, FONT);
    });
}

/// Encodes 8-bit pixels as PNG file bytes: `channels` is 3 (RGB) or 4 (RGBA), rows top to
/// bottom, `width * height * channels` bytes. The one PNG writer shared by the image nodes
/// and the charts.
pub fn encode_png(width: u32, height: u32, channels: u8, data: Vec<u8>) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    let mut cur = std::io::Cursor::new(&mut out);
    let res = match channels {
        3 => image::RgbImage::from_raw(width, height, data)
            .ok_or("bad buffer")?
            .write_to(&mut cur, image::ImageFormat::Png),
        4 => image::RgbaImage::from_raw(width, height, data)
            .ok_or("bad buffer")?
            .write_to(&mut cur, image::ImageFormat::Png),
        c => return Err(format!("PNG with {c} channels is not supported")),
    };
    res.map_err(|e| e.to_string())?;
    Ok(out)
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
