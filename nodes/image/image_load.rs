//! `image_load`: reads an image file as linear RGBA.
//!
//! 8- and 16-bit files (PNG, JPEG) are sRGB-encoded by convention and decoded to linear
//! with the exact sRGB transfer function (IEC 61966-2-1); float files (EXR, HDR) are linear
//! already.

use super::srgb::srgb_to_linear;
use crate::prelude::*;
use std::io::Cursor;

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

fn declare(b: &mut NodeBuilder) {
    b.doc("Reads an image (PNG, JPEG, EXR, HDR) as linear RGBA.");
    b.add_input::<String>("path")
        .file_in()
        .doc("Image file, relative to the graph's folder.");
    b.add_choice::<ColorSpace>("color_space")
        .doc("8/16-bit files: srgb decodes colour to linear; raw keeps data (normal maps).");
    b.add_output::<Image>("image");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let p: String = ctx.input("path")?;
    let space = ctx.choice::<ColorSpace>("color_space")?;
    let path = ctx.input_path(&p);
    let bytes = std::fs::read(&path).map_err(|e| NodeError::io(&path, e).at("path"))?;
    // The declared size is checked before decoding: up to 16 bytes per pixel decoded, 16
    // converted and 16 in the output image.
    let (w, h) = image_dimensions(&bytes).map_err(|e| NodeError::io(&path, e).at("path"))?;
    let what = format!("{}: a {w}x{h} image", path.display());
    ctx.reserve_bytes("path", &what, crate::node::bytes_of(&[w as u64, h as u64, 48]))?;
    let img = decode_image(&bytes, space).map_err(|e| NodeError::io(&path, e).at("path"))?;
    ctx.set_output("image", img);
    Ok(())
}

/// Registers `image_load`.
pub fn register(r: &mut Registry) {
    r.add("image_load", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// BMP (a common texture format in MTL files) decodes like PNG. (TGA has no signature to
    /// recognise it by, so it would need the file extension; it is not read.)
    #[test]
    fn bmp_textures_decode() {
        let px = image::RgbImage::from_raw(2, 1, vec![255, 0, 0, 0, 0, 255]).unwrap();
        let mut bytes = Vec::new();
        px.write_to(&mut Cursor::new(&mut bytes), image::ImageFormat::Bmp)
            .unwrap();
        let img = decode_image(&bytes, ColorSpace::Raw).unwrap();
        assert_eq!((img.width, img.height), (2, 1));
        let first = img.pixels[0];
        assert!((first[0] - 1.0).abs() < 1e-6 && first[2].abs() < 1e-6, "{first:?}");
    }
}
