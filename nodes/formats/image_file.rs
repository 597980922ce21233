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
        ImageFileFormat::Exr => {
            let data: Vec<f32> = img
                .pixels
                .iter()
                .flat_map(|p| [lin(p[0]), lin(p[1]), lin(p[2]), p[3]])
                .collect();
            let buf = image::Rgba32FImage::from_raw(w, h, data).ok_or("bad buffer")?;
            buf.write_to(&mut cur, image::ImageFormat::OpenExr)
        }
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
