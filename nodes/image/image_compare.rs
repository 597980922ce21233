//! `image_compare`: RMSE and PSNR of an image against a reference, optionally inside a mask.

use cgnodes_api::prelude::*;

/// Why two images cannot be compared.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CompareError {
    /// The image and the reference differ in size (width, height of each).
    #[error("image is {}x{} but the reference is {}x{}", image.0, image.1, reference.0, reference.1)]
    SizeMismatch {
        image: (u32, u32),
        reference: (u32, u32),
    },
    /// The mask differs in size from the image.
    #[error("mask is {}x{} but the image is {}x{}", mask.0, mask.1, image.0, image.1)]
    MaskSize { mask: (u32, u32), image: (u32, u32) },
    /// The difference at pixel `index` (row-major) is NaN or infinite.
    #[error("pixel {index} is not finite")]
    NonFinite { index: usize },
    /// No pixel of the mask has luminance above one half.
    #[error("the mask selects no pixel")]
    EmptyMask,
}

/// Root-mean-square error over the RGB channels of the pixels where `mask` (if any) has
/// luminance above one half, and the PSNR for a signal peak of `peak`. Returns
/// (rmse, psnr, pixels compared).
pub fn image_rmse(
    image: &Image,
    reference: &Image,
    mask: Option<&Image>,
    peak: f64,
) -> Result<(f64, f64, usize), CompareError> {
    let size = |i: &Image| (i.width, i.height);
    if size(image) != size(reference) {
        return Err(CompareError::SizeMismatch {
            image: size(image),
            reference: size(reference),
        });
    }
    if let Some(m) = mask {
        if size(m) != size(image) {
            return Err(CompareError::MaskSize {
                mask: size(m),
                image: size(image),
            });
        }
    }
    let mut sum = 0.0f64;
    let mut n = 0usize;
    for (i, (a, b)) in image.pixels.iter().zip(&reference.pixels).enumerate() {
        if let Some(m) = mask {
            let p = m.pixels[i];
            if 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2] <= 0.5 {
                continue;
            }
        }
        for c in 0..3 {
            let d = a[c] as f64 - b[c] as f64;
            if !d.is_finite() {
                return Err(CompareError::NonFinite { index: i });
            }
            sum += d * d;
        }
        n += 1;
    }
    if n == 0 {
        return Err(CompareError::EmptyMask);
    }
    let rmse = (sum / (3 * n) as f64).sqrt();
    // PSNR = 20 log10(peak / RMSE); infinite for identical images.
    let psnr = if rmse > 0.0 {
        20.0 * (peak / rmse).log10()
    } else {
        f64::INFINITY
    };
    Ok((rmse, psnr, n))
}

fn declare(b: &mut NodeBuilder) {
    b.doc("RMSE and PSNR of an image against a reference (optionally inside a mask).");
    b.add_input::<Image>("image");
    b.add_input::<Image>("reference");
    b.add_input::<Image>("mask")
        .optional()
        .doc("Pixels with luminance above 0.5 are compared.");
    b.add_input::<f64>("peak")
        .default(1.0)
        .min(1e-12)
        .doc("Signal peak for PSNR.");
    b.add_output::<f64>("rmse");
    b.add_output::<f64>("psnr");
    b.add_output::<Table>("table");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let img: Arc<Image> = ctx.input("image")?;
    let reference: Arc<Image> = ctx.input("reference")?;
    let mask: Option<Arc<Image>> = ctx.input_opt("mask")?;
    let peak: f64 = ctx.input("peak")?;
    let (rmse, psnr, n) = image_rmse(&img, &reference, mask.as_deref(), peak)
        .map_err(|e| NodeError::invalid("reference", e.to_string()))?;
    ctx.set_output("rmse", rmse);
    ctx.set_output("psnr", psnr);
    ctx.set_output(
        "table",
        Table::from_row(&[("rmse", rmse), ("psnr", psnr), ("pixels", n as f64)]),
    );
    Ok(())
}

/// Registers `image_compare`.
pub fn register(r: &mut Registry) {
    r.add("image_compare", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rmse_and_psnr_of_a_constant_offset() {
        let a = Image::new(4, 3, [0.5, 0.5, 0.5, 1.0]);
        let b = Image::new(4, 3, [0.6, 0.5, 0.4, 1.0]);
        let (rmse, psnr, n) = image_rmse(&a, &b, None, 1.0).unwrap();
        // errors 0.1, 0, 0.1 per pixel: RMSE = sqrt(0.02 / 3)
        assert!((rmse - (0.02f64 / 3.0).sqrt()).abs() < 1e-7);
        assert!((psnr - 20.0 * (1.0 / rmse).log10()).abs() < 1e-9);
        assert_eq!(n, 12);
        let mut mask = Image::new(4, 3, [0.0; 4]);
        mask.set(1, 1, [1.0; 4]);
        assert_eq!(image_rmse(&a, &b, Some(&mask), 1.0).unwrap().2, 1);
        assert!(image_rmse(&a, &Image::new(2, 2, [0.0; 4]), None, 1.0).is_err());
        assert!(image_rmse(&a, &a, Some(&Image::new(4, 3, [0.0; 4])), 1.0).is_err());
        assert_eq!(image_rmse(&a, &a, None, 1.0).unwrap().1, f64::INFINITY);
    }
}
