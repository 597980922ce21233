//! Structural checks of image files before decoding: a file that was cut short or damaged
//! must be an error, never a partial image. Some decoders fill missing rows with zeros (a
//! PNG cut inside its pixel data) or grey (a JPEG without its end), so the container is
//! walked here first: PNG chunks with their CRCs up to `IEND` (PNG specification, 3rd ed.,
//! section 5), JPEG markers up to `EOI` (ITU-T T.81, annex B), GIF blocks up to the trailer
//! (GIF89a, section 27), and a BMP's pixel array against the size its header declares.
//! EXR and HDR decoders already fail on a short read; they are checked by decoding.

/// Why an image file is cut short or damaged: the format, and the byte at fault where known.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum IncompleteImage {
    /// The PNG ends before its `IEND` chunk, between chunks.
    #[error("truncated PNG: the file ends at byte {len} before its IEND chunk")]
    PngEnds {
        /// The file's length.
        len: usize,
    },
    /// A PNG chunk runs past the end of the file.
    #[error("truncated PNG: chunk '{kind}' at byte {at} needs {need} bytes, {remain} remain")]
    PngChunk {
        /// The chunk type.
        kind: String,
        /// Its offset.
        at: usize,
        /// Its length with header and CRC.
        need: usize,
        /// The bytes left from `at`.
        remain: usize,
    },
    /// A PNG chunk's CRC-32 does not match.
    #[error("corrupted PNG: chunk '{kind}' at byte {at} fails its CRC check")]
    PngCrc {
        /// The chunk type.
        kind: String,
        /// Its offset.
        at: usize,
    },
    /// The JPEG ends before its `EOI` marker.
    #[error("truncated JPEG: the file ends before its end-of-image marker")]
    JpegEnds,
    /// No JPEG marker where one must be.
    #[error("corrupted JPEG: no marker at byte {at}")]
    JpegNoMarker {
        /// The offset.
        at: usize,
    },
    /// A JPEG segment length under 2.
    #[error("corrupted JPEG: segment length {len} at byte {at}")]
    JpegSegmentLength {
        /// The length read.
        len: usize,
        /// Its offset.
        at: usize,
    },
    /// The GIF ends before its trailer.
    #[error("truncated GIF: the file ends before its trailer")]
    GifEnds,
    /// A GIF block of unknown type.
    #[error("corrupted GIF: unknown block 0x{block:02X} at byte {at}")]
    GifBlock {
        /// The block's introducer byte.
        block: u8,
        /// Its offset.
        at: usize,
    },
    /// The BMP ends inside its header.
    #[error("truncated BMP: the file ends inside its header")]
    BmpHeader,
    /// The BMP's pixel array does not fit in the file.
    #[error("truncated BMP: its {width}x{height} pixels need {need} bytes, the file has {len}")]
    BmpPixels {
        /// Width in pixels.
        width: i64,
        /// Height in pixels.
        height: i64,
        /// Bytes the header implies.
        need: i64,
        /// The file's length.
        len: usize,
    },
}

/// The decoders report errors as text: the message unchanged.
impl From<IncompleteImage> for String {
    fn from(e: IncompleteImage) -> String {
        e.to_string()
    }
}

/// Checks that `bytes` holds a complete, undamaged image container of the format its magic
/// number names; other formats pass unchecked.
pub fn check_complete(bytes: &[u8]) -> Result<(), IncompleteImage> {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        check_png(bytes)
    } else if bytes.starts_with(&[0xFF, 0xD8]) {
        check_jpeg(bytes)
    } else if bytes.starts_with(b"GIF87a") || bytes.starts_with(b"GIF89a") {
        check_gif(bytes)
    } else if bytes.starts_with(b"BM") {
        check_bmp(bytes)
    } else {
        Ok(())
    }
}

fn be32(b: &[u8], at: usize) -> u32 {
    u32::from_be_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn le32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

/// PNG: every chunk whole, its CRC-32 (over type and data) right, and an `IEND` chunk.
fn check_png(b: &[u8]) -> Result<(), IncompleteImage> {
    let mut at = 8;
    loop {
        if b.len() < at + 8 {
            return Err(IncompleteImage::PngEnds { len: b.len() });
        }
        let len = be32(b, at) as usize;
        let kind = String::from_utf8_lossy(&b[at + 4..at + 8]).into_owned();
        let end = at
            .checked_add(12)
            .and_then(|x| x.checked_add(len))
            .filter(|&e| e <= b.len())
            .ok_or_else(|| IncompleteImage::PngChunk {
                kind: kind.clone(),
                at,
                need: len.saturating_add(12),
                remain: b.len() - at,
            })?;
        let stored = be32(b, end - 4);
        if crc32fast::hash(&b[at + 4..end - 4]) != stored {
            return Err(IncompleteImage::PngCrc { kind, at });
        }
        if kind == "IEND" {
            return Ok(());
        }
        at = end;
    }
}

/// JPEG: marker segments and entropy-coded scans walked up to the `EOI` marker.
fn check_jpeg(b: &[u8]) -> Result<(), IncompleteImage> {
    let short = || IncompleteImage::JpegEnds;
    let mut at = 2;
    loop {
        // Fill bytes (0xFF) may precede a marker.
        while at < b.len() && b[at] == 0xFF && at + 1 < b.len() && b[at + 1] == 0xFF {
            at += 1;
        }
        if at + 2 > b.len() {
            return Err(short());
        }
        if b[at] != 0xFF {
            return Err(IncompleteImage::JpegNoMarker { at });
        }
        let m = b[at + 1];
        at += 2;
        match m {
            0xD9 => return Ok(()),
            // Markers without a length: TEM and RST0-7.
            0x01 | 0xD0..=0xD7 => continue,
            _ => {}
        }
        if at + 2 > b.len() {
            return Err(short());
        }
        let len = u16::from_be_bytes([b[at], b[at + 1]]) as usize;
        if len < 2 {
            return Err(IncompleteImage::JpegSegmentLength { len, at });
        }
        at += len;
        if at > b.len() {
            return Err(short());
        }
        if m == 0xDA {
            // Entropy-coded data: runs until a marker other than a stuffed 0xFF00 or RSTn.
            loop {
                if at + 1 >= b.len() {
                    return Err(short());
                }
                if b[at] == 0xFF && b[at + 1] != 0x00 && !(0xD0..=0xD7).contains(&b[at + 1]) {
                    break;
                }
                at += 1;
            }
        }
    }
}

/// GIF: header, colour tables, extension and image blocks up to the trailer (`;`).
fn check_gif(b: &[u8]) -> Result<(), IncompleteImage> {
    let short = || IncompleteImage::GifEnds;
    if b.len() < 13 {
        return Err(short());
    }
    let table = |flags: u8| {
        if flags & 0x80 != 0 {
            3usize << ((flags & 7) + 1)
        } else {
            0
        }
    };
    let mut at = 13 + table(b[10]);
    // Data sub-blocks: a length byte, then that many bytes, until a zero length.
    let sub_blocks = |mut at: usize| -> Option<usize> {
        loop {
            let n = *b.get(at)? as usize;
            at += 1 + n;
            if n == 0 {
                return Some(at);
            }
        }
    };
    loop {
        match b.get(at).copied() {
            None => return Err(short()),
            Some(0x3B) => return Ok(()),
            Some(0x21) => at = sub_blocks(at + 2).ok_or_else(short)?,
            Some(0x2C) => {
                let flags = *b.get(at + 9).ok_or_else(short)?;
                at += 10 + table(flags) + 1; // descriptor, local table, LZW code size
                at = sub_blocks(at).ok_or_else(short)?;
            }
            Some(x) => return Err(IncompleteImage::GifBlock { block: x, at }),
        }
        if at > b.len() {
            return Err(short());
        }
    }
}

/// BMP: the uncompressed pixel array the header declares fits in the file.
fn check_bmp(b: &[u8]) -> Result<(), IncompleteImage> {
    if b.len() < 30 {
        return Err(IncompleteImage::BmpHeader);
    }
    let offset = le32(b, 10) as u64;
    let header = le32(b, 14);
    if (b.len() as u64) < 14 + header as u64 {
        return Err(IncompleteImage::BmpHeader);
    }
    if header < 40 {
        return Ok(()); // OS/2 core headers: left to the decoder
    }
    let width = le32(b, 18) as i32 as i64;
    let height = (le32(b, 22) as i32 as i64).abs();
    let bits = u16::from_le_bytes([b[28], b[29]]) as i64;
    let compression = le32(b, 30);
    if compression != 0 && compression != 3 {
        return Ok(()); // RLE: the decoder reads to the end-of-bitmap code
    }
    let stride = (width.abs() * bits + 31) / 32 * 4;
    let need = offset as i64 + stride * height;
    if (b.len() as i64) < need {
        return Err(IncompleteImage::BmpPixels {
            width: width.abs(),
            height,
            need,
            len: b.len(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::check_complete;
    use image::{ImageFormat, RgbaImage};

    fn encoded(format: ImageFormat) -> Vec<u8> {
        let img = RgbaImage::from_fn(64, 64, |x, y| {
            image::Rgba([(x * 4) as u8, (y * 4) as u8, ((x ^ y) * 3) as u8, 255])
        });
        let mut out = std::io::Cursor::new(Vec::new());
        match format {
            ImageFormat::Jpeg | ImageFormat::Bmp => image::DynamicImage::ImageRgba8(img)
                .to_rgb8()
                .write_to(&mut out, format)
                .unwrap(),
            _ => img.write_to(&mut out, format).unwrap(),
        }
        out.into_inner()
    }

    #[test]
    fn whole_files_pass_and_every_cut_fails() {
        for f in [
            ImageFormat::Png,
            ImageFormat::Jpeg,
            ImageFormat::Gif,
            ImageFormat::Bmp,
        ] {
            let b = encoded(f);
            check_complete(&b).unwrap_or_else(|e| panic!("{f:?}: {e}"));
            // Every cut past the magic number is refused (BMP: past its headers).
            let first = match f {
                ImageFormat::Png => 8,
                ImageFormat::Gif => 6,
                ImageFormat::Bmp => 54,
                _ => 2,
            };
            for cut in first..b.len() {
                assert!(
                    check_complete(&b[..cut]).is_err(),
                    "{f:?} cut at {cut} of {}",
                    b.len()
                );
            }
        }
    }

    #[test]
    fn a_flipped_png_byte_fails_its_crc() {
        let mut b = encoded(ImageFormat::Png);
        let i = b.len() / 2;
        b[i] ^= 0x40;
        let e = check_complete(&b).unwrap_err().to_string();
        assert!(e.contains("CRC"), "{e}");
    }
}
