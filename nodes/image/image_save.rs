//! `image_save`: writes an image file, linear inside.
//!
//! `.png` is written 8-bit with the sRGB curve (or a power `gamma`), `.exr` and `.hdr` as
//! linear floats; `exposure` (in stops) scales all of them.

use cgnodes_api::prelude::*;
pub use cgnodes_formats::image_file::{encode_image, ImageFileFormat};

fn declare(b: &mut NodeBuilder) {
    b.doc("Writes an image: .png 8-bit sRGB, .exr and .hdr linear float (by extension).");
    b.sink();
    b.add_input::<Image>("image");
    b.add_input::<String>("path")
        .file_out()
        .doc("Output file (.png, .exr or .hdr); may contain {frame}.");
    b.add_input::<f64>("exposure")
        .default(0.0)
        .range(-64.0, 64.0)
        .doc("Exposure in stops: colour is scaled by 2^exposure.");
    b.add_input::<f64>("gamma")
        .default(0.0)
        .range(0.0, 10.0)
        .doc("PNG encoding: 0 = the sRGB curve, else the power 1/gamma.");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let img: Arc<Image> = ctx.input("image")?;
    let p: String = ctx.input("path")?;
    let exposure: f64 = ctx.input("exposure")?;
    let gamma: f64 = ctx.input("gamma")?;
    if !exposure.is_finite() {
        return Err(NodeError::invalid("exposure", "must be finite"));
    }
    if !(gamma.is_finite() && gamma >= 0.0) {
        return Err(NodeError::invalid("gamma", "must be >= 0"));
    }
    let path = ctx.output_path("path", &p)?;
    let fmt = ImageFileFormat::from_path(&path).ok_or_else(|| {
        NodeError::invalid(
            "path",
            format!("'{p}': extension must be .png, .exr or .hdr"),
        )
    })?;
    let bytes =
        encode_image(&img, fmt, exposure, gamma).map_err(|e| NodeError::invalid("image", e))?;
    ctx.write_file(&path, &bytes)?;
    // With no exposure or gamma change the file shows the image as it is: the run report
    // draws it from memory.
    if exposure == 0.0 && gamma == 0.0 {
        ctx.wrote_from(&path, Value::Image(img));
    }
    Ok(())
}

/// Registers `image_save`.
pub fn register(r: &mut Registry) {
    r.add("image_save", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;
    use cgnodes_formats::image_file::{decode_image, ColorSpace};
    use std::collections::BTreeMap;

    fn test_image() -> Image {
        let mut img = Image::new(3, 2, [0.0, 0.0, 0.0, 1.0]);
        img.set(0, 0, [1.0, 0.5, 0.25, 1.0]);
        img.set(2, 1, [0.01, 2.0, 0.0, 0.5]);
        img
    }

    #[test]
    fn png_round_trip_within_8_bit_precision() {
        let img = test_image();
        let bytes = encode_image(&img, ImageFileFormat::Png, 0.0, 0.0).unwrap();
        let back = decode_image(&bytes, ColorSpace::Srgb).unwrap();
        assert_eq!((back.width, back.height), (3, 2));
        for (a, b) in img.pixels.iter().zip(&back.pixels) {
            for k in 0..4 {
                let want = if k < 3 { a[k].min(1.0) } else { a[k] };
                // One 8-bit step of the sRGB curve is at most ~1.3% of linear at the top.
                assert!((want - b[k]).abs() < 0.01, "{a:?} vs {b:?}");
            }
        }
        // Raw decoding keeps the stored code values: sRGB(0.5 linear) = 188/255.
        let raw = decode_image(&bytes, ColorSpace::Raw).unwrap();
        assert!((raw.get(0, 0)[1] - 188.0 / 255.0).abs() < 1e-6);
    }

    #[test]
    fn exposure_and_gamma() {
        let img = Image::new(1, 1, [0.25, 0.25, 0.25, 1.0]);
        // One stop up doubles linear 0.25 to 0.5; gamma 1 stores it linearly: 128.
        let bytes = encode_image(&img, ImageFileFormat::Png, 1.0, 1.0).unwrap();
        let raw = decode_image(&bytes, ColorSpace::Raw).unwrap();
        assert!((raw.get(0, 0)[0] - 128.0 / 255.0).abs() < 1e-6);
        // gamma 2: sqrt(0.25) = 0.5.
        let bytes = encode_image(&img, ImageFileFormat::Png, 0.0, 2.0).unwrap();
        let raw = decode_image(&bytes, ColorSpace::Raw).unwrap();
        assert!((raw.get(0, 0)[0] - 128.0 / 255.0).abs() < 1e-6);
    }

    #[test]
    fn float_formats_keep_linear_values() {
        let img = test_image();
        let exr = encode_image(&img, ImageFileFormat::Exr, 0.0, 0.0).unwrap();
        let back = decode_image(&exr, ColorSpace::Srgb).unwrap();
        assert_eq!(back.pixels, img.pixels);
        let hdr = encode_image(&img, ImageFileFormat::Hdr, 0.0, 0.0).unwrap();
        let back = decode_image(&hdr, ColorSpace::Srgb).unwrap();
        // RGBE keeps 8 mantissa bits relative to the largest channel.
        let p = back.get(2, 1);
        assert!((p[1] - 2.0).abs() < 0.02 && p[0] < 0.02);
        assert!((back.get(0, 0)[2] - 0.25).abs() < 0.005);
    }

    #[test]
    fn nodes_write_and_read_files() {
        let dir = tempfile::tempdir().unwrap();
        let mut r = Registry::new();
        crate::register(&mut r);
        let files = FileEnv {
            graph_dir: dir.path().join("out"),
            out_dir: dir.path().join("out"),
            ..Default::default()
        };
        let decl = r.get("image_save").unwrap();
        let mut inp = BTreeMap::new();
        inp.insert("image".into(), Value::from(test_image()));
        inp.insert("path".into(), Value::from("sub/a.png"));
        let mut state = None;
        let mut ctx = ExecContext::standalone(decl, inp, &mut state, &files, 0);
        (decl.exec.as_ref().unwrap())(&mut ctx).unwrap();
        assert!(dir.path().join("out/sub/a.png").exists());

        let decl = r.get("image_load").unwrap();
        let mut inp = BTreeMap::new();
        inp.insert("path".into(), Value::from("sub/a.png"));
        let mut ctx = ExecContext::standalone(decl, inp, &mut state, &files, 0);
        (decl.exec.as_ref().unwrap())(&mut ctx).unwrap();
        match &ctx.take_outputs()["image"] {
            Value::Image(i) => assert!((i.get(0, 0)[1] - 0.5).abs() < 0.01),
            _ => panic!(),
        }

        // A missing file, a corrupt file and an unknown extension are errors, not panics.
        std::fs::write(dir.path().join("out/bad.png"), b"not a png").unwrap();
        for p in ["missing.png", "bad.png"] {
            let mut inp = BTreeMap::new();
            inp.insert("path".into(), Value::from(p));
            let mut ctx = ExecContext::standalone(decl, inp, &mut state, &files, 0);
            assert!((decl.exec.as_ref().unwrap())(&mut ctx).is_err());
        }
        let decl = r.get("image_save").unwrap();
        let mut inp = BTreeMap::new();
        inp.insert("image".into(), Value::from(test_image()));
        inp.insert("path".into(), Value::from("a.bmp"));
        let mut ctx = ExecContext::standalone(decl, inp, &mut state, &files, 0);
        assert!((decl.exec.as_ref().unwrap())(&mut ctx).is_err());
    }
}
