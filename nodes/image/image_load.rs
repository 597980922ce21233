//! `image_load`: reads an image file as linear RGBA.
//!
//! 8- and 16-bit files (PNG, JPEG) are sRGB-encoded by convention and decoded to linear
//! with the exact sRGB transfer function (IEC 61966-2-1); float files (EXR, HDR) are linear
//! already.

use cgnodes_api::prelude::*;
pub use cgnodes_formats::image_file::{decode_image, image_dimensions, ColorSpace};

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
    ctx.reserve_bytes(
        "path",
        &what,
        cgnodes_api::node::bytes_of(&[w as u64, h as u64, 48]),
    )?;
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
        px.write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Bmp,
        )
        .unwrap();
        let img = decode_image(&bytes, ColorSpace::Raw).unwrap();
        assert_eq!((img.width, img.height), (2, 1));
        let first = img.pixels[0];
        assert!(
            (first[0] - 1.0).abs() < 1e-6 && first[2].abs() < 1e-6,
            "{first:?}"
        );
    }
}
