//! PNG encoding of 8-bit pixel buffers, shared by the image writers and the charts.

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
