//! Image files in and out: decoding PNG, JPEG, EXR, HDR, BMP and GIF to linear RGBA and
//! encoding linear RGBA to those formats, with the sRGB transfer functions (IEC 61966-2-1).

use crate::srgb::{linear_to_srgb, srgb_to_linear};
use cgnodes_api::prelude::*;
use std::io::Cursor;
use std::path::Path;

/// How the stored values of an 8- or 16-bit file map to the image's values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorSpace {
    /// sRGB-encoded colour: decoded to linear.
    Srgb,
    /// Data (normal maps, masks): values taken as they are, scaled to 0..1.
    Raw,
}

impl Choice for ColorSpace {
    const CHOICES: &'static [(&'static str, Self)] =
        &[("srgb", ColorSpace::Srgb), ("raw", ColorSpace::Raw)];
}

/// An RGBA float EXR of `img` with `lin` applied to the colour: RLE-compressed scanline
/// blocks in increasing y, so the bytes depend only on the pixels (blocks compressed in
/// parallel are written in order) and every OpenEXR reader takes the file.
fn encode_exr(img: &Image, lin: impl Fn(f32) -> f32 + Sync) -> Result<Vec<u8>, String> {
    use exr::prelude::{Encoding, Image as ExrImage, SpecificChannels, Vec2, WritableImage};
    let (w, h) = (img.width as usize, img.height as usize);
    let channels = SpecificChannels::rgba(|p: Vec2<usize>| {
        let c = img.pixels[p.y() * w + p.x()];
        (lin(c[0]), lin(c[1]), lin(c[2]), c[3])
    });
    let encoding = Encoding {
        compression: exr::compression::Compression::RLE,
        blocks: exr::image::Blocks::ScanLines,
        line_order: exr::meta::attribute::LineOrder::Increasing,
    };
    let image = ExrImage::from_encoded_channels((w, h), encoding, channels);
    let mut out = Vec::new();
    image
        .write()
        .to_buffered(Cursor::new(&mut out))
        .map_err(|e| e.to_string())?;
    Ok(out)
}

/// The width and height an image file declares, read from its header without decoding.
pub fn image_dimensions(bytes: &[u8]) -> Result<(u32, u32), String> {
    image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())?
        .into_dimensions()
        .map_err(|e| e.to_string())
}

/// Decodes image file bytes to a linear RGBA image (see the module doc for the rules).
/// A truncated or damaged file is an error (`file_check`), never a partial image.
pub fn decode_image(bytes: &[u8], space: ColorSpace) -> Result<Image, String> {
    super::file_check::check_complete(bytes)?;
    let dynimg = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())?
        .decode()
        .map_err(|e| e.to_string())?;
    let (w, h) = (dynimg.width(), dynimg.height());
    use image::ColorType as C;
    let pixels: Vec<[f32; 4]> = match dynimg.color() {
        C::Rgb32F | C::Rgba32F => dynimg.to_rgba32f().pixels().map(|p| p.0).collect(),
        C::L16 | C::La16 | C::Rgb16 | C::Rgba16 => dynimg
            .to_rgba16()
            .pixels()
            .map(|p| {
                let f = |v: u16| v as f32 / 65535.0;
                let c = |v: u16| match space {
                    ColorSpace::Srgb => srgb_to_linear(f(v)),
                    ColorSpace::Raw => f(v),
                };
                [c(p.0[0]), c(p.0[1]), c(p.0[2]), f(p.0[3])]
            })
            .collect(),
        _ => {
            let lut: Vec<f32> = (0..256)
                .map(|v| match space {
                    ColorSpace::Srgb => srgb_to_linear(v as f32 / 255.0),
                    ColorSpace::Raw => v as f32 / 255.0,
                })
                .collect();
            dynimg
                .to_rgba8()
                .pixels()
                .map(|p| {
                    [
                        lut[p.0[0] as usize],
                        lut[p.0[1] as usize],
                        lut[p.0[2] as usize],
                        p.0[3] as f32 / 255.0,
                    ]
                })
                .collect()
        }
    };
    Ok(Image {
        width: w,
        height: h,
        pixels,
    })
}

/// The file formats `image_save` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFileFormat {
    /// 8-bit RGBA PNG, tone-encoded (sRGB curve or a power).
    Png,
    /// 32-bit float RGBA OpenEXR, linear.
    Exr,
    /// Radiance RGBE, linear RGB.
    Hdr,
}

impl ImageFileFormat {
    /// The format named by a path's extension.
    pub fn from_path(p: &Path) -> Option<ImageFileFormat> {
        let ext = p.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "png" => Some(ImageFileFormat::Png),
            "exr" => Some(ImageFileFormat::Exr),
            "hdr" => Some(ImageFileFormat::Hdr),
            _ => None,
        }
    }
}

/// Encodes an image to file bytes. `exposure` scales colour by 2^exposure; for PNG,
/// `gamma` = 0 applies the sRGB curve and `gamma` > 0 the power 1/gamma. Alpha is stored
/// linearly. Non-finite values are written as 0.
pub fn encode_image(
    img: &Image,
    format: ImageFileFormat,
    exposure: f64,
    gamma: f64,
) -> Result<Vec<u8>, String> {
    if img.pixels.len() != img.width as usize * img.height as usize || img.width == 0 {
        return Err(format!(
            "image {}x{} has {} pixels",
            img.width,
            img.height,
            img.pixels.len()
        ));
    }
    let k = 2f32.powf(exposure as f32);
    let lin = |v: f32| if v.is_finite() { v * k } else { 0.0 };
    let mut out = Vec::new();
    let mut cur = Cursor::new(&mut out);
    let (w, h) = (img.width, img.height);
    let res = match format {
        ImageFileFormat::Png => {
            let enc = |v: f32| -> u8 {
                let e = if gamma > 0.0 {
                    let v = lin(v).clamp(0.0, 1.0);
                    v.powf(1.0 / gamma as f32)
                } else {
                    linear_to_srgb(lin(v))
                };
                (e * 255.0 + 0.5).clamp(0.0, 255.0) as u8
            };
            let a8 = |v: f32| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
            let data: Vec<u8> = img
                .pixels
                .iter()
                .flat_map(|p| [enc(p[0]), enc(p[1]), enc(p[2]), a8(p[3])])
                .collect();
            return crate::png::encode_png(w, h, 4, data);
        }
        ImageFileFormat::Exr => return encode_exr(img, lin),
        ImageFileFormat::Hdr => {
            let data: Vec<f32> = img
                .pixels
                .iter()
                .flat_map(|p| [lin(p[0]).max(0.0), lin(p[1]).max(0.0), lin(p[2]).max(0.0)])
                .collect();
            let buf = image::Rgb32FImage::from_raw(w, h, data).ok_or("bad buffer")?;
            buf.write_to(&mut cur, image::ImageFormat::Hdr)
        }
    };
    res.map_err(|e| e.to_string())?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// EXR files hold the pixels exactly (non-finite colour written as 0), as increasing
    /// scanlines, byte for byte the same on every write: the 64x64 tiles image 0.25 writes
    /// come in thread order, and OpenEXR refused about one such file in a hundred.
    #[test]
    fn exr_is_exact_ordered_scanlines() {
        let (w, h) = (300u32, 170u32);
        let pixels: Vec<[f32; 4]> = (0..w * h)
            .map(|i| {
                let x = (i as f32 * 0.618_034).fract();
                let c = if i % 97 == 0 { f32::NAN } else { x * 7.0 };
                [c, x, 1.0 - x, 0.5]
            })
            .collect();
        let img = Image {
            width: w,
            height: h,
            pixels,
        };
        let a = encode_image(&img, ImageFileFormat::Exr, 0.0, 0.0).unwrap();
        for _ in 0..4 {
            assert_eq!(
                encode_image(&img, ImageFileFormat::Exr, 0.0, 0.0).unwrap(),
                a
            );
        }
        let back = decode_image(&a, ColorSpace::Raw).unwrap();
        assert_eq!((back.width, back.height), (w, h));
        for (p, q) in img.pixels.iter().zip(&back.pixels) {
            let c = |v: f32| if v.is_finite() { v } else { 0.0 };
            assert_eq!([c(p[0]), p[1], p[2], p[3]], *q);
        }
        let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(&a), false).unwrap();
        let head = &meta.headers[0];
        assert_eq!(head.blocks, exr::meta::BlockDescription::ScanLines);
        assert_eq!(head.line_order, exr::meta::attribute::LineOrder::Increasing);
    }
}
