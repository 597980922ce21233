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

/// Encodes 8-bit RGBA pixels (rows top to bottom) as PNG with fast compression (fdeflate):
/// larger files, several times faster to write; for thumbnails made on every run.
pub fn encode_png_fast(width: u32, height: u32, rgba: &[u8]) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    let mut enc = ::png::Encoder::new(&mut out, width, height);
    enc.set_color(::png::ColorType::Rgba);
    enc.set_depth(::png::BitDepth::Eight);
    enc.set_compression(::png::Compression::Fast);
    let mut w = enc.write_header().map_err(|e| e.to_string())?;
    w.write_image_data(rgba).map_err(|e| e.to_string())?;
    w.finish().map_err(|e| e.to_string())?;
    Ok(out)
}
