//! `image_svd`: low-rank image compression by the truncated SVD of each channel (the
//! course's §3.1 task), exact (faer) or randomized (Halko, Martinsson & Tropp 2011). The
//! algorithms are in `svd/`; this file splits the image into channel matrices and back.

#[path = "svd/mod.rs"]
pub mod svd;

use cgnodes_api::prelude::*;
use faer::Mat;
use svd::{Method, RandomizedParams, Truncation};

/// Rec. 709 luminance weights of linear RGB, for the grayscale variant.
const LUMA: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// One channel's result.
#[derive(Clone, Debug)]
pub struct ChannelResult {
    /// Rank kept.
    pub rank: usize,
    /// PSNR against the channel (peak 1), dB.
    pub psnr: f64,
    /// ||A - A_k||_F / ||A||_F (0 for a zero channel reproduced exactly).
    pub rel_error: f64,
    /// (m + n + 1) k / (m n): the numbers stored for rank k against the pixels.
    pub storage_ratio: f64,
    /// The singular values computed.
    pub singular_values: Vec<f64>,
}

/// The result of `image_svd`.
#[derive(Clone, Debug)]
pub struct Compressed {
    /// The reconstruction (alpha copied from the input; values not clamped).
    pub image: Image,
    /// One entry per channel: R, G, B, or one for the grayscale variant.
    pub channels: Vec<ChannelResult>,
}

/// The channel matrices of `img`, transposed (width x height, so that the column-major
/// matrix walks the row-major pixels in order; the SVD of A^T is that of A transposed, with
/// the same singular values): R, G, B, or its luminance.
pub fn channel_matrices(img: &Image, grayscale: bool) -> Vec<Mat<f64>> {
    let (w, h) = (img.width as usize, img.height as usize);
    let px = |x: usize, y: usize| img.pixels[y * w + x];
    if grayscale {
        vec![Mat::from_fn(w, h, |x, y| {
            let p = px(x, y);
            (0..3).map(|c| LUMA[c] * p[c] as f64).sum()
        })]
    } else {
        (0..3)
            .map(|c| Mat::from_fn(w, h, |x, y| px(x, y)[c] as f64))
            .collect()
    }
}

/// Compresses every channel of `img` to a low rank (a rank above min(m, n) is clamped; the
/// caller warns). Errors name the socket at fault.
pub fn image_svd(
    img: &Image,
    trunc: Truncation,
    method: Method,
    params: RandomizedParams,
    grayscale: bool,
) -> Result<Compressed, NodeError> {
    if img.width == 0 || img.height == 0 {
        return Err(NodeError::invalid("image", "the image is empty"));
    }
    if let Some(i) = img
        .pixels
        .iter()
        .position(|p| p.iter().any(|v| !v.is_finite()))
    {
        let w = img.width as usize;
        return Err(NodeError::invalid(
            "image",
            format!("pixel ({}, {}) is not finite", i % w, i / w),
        ));
    }
    let (m, n) = (img.height as usize, img.width as usize);
    let mut out = img.clone();
    let mut channels = Vec::new();
    for (c, a) in channel_matrices(img, grayscale).iter().enumerate() {
        let approx = svd::low_rank(a.as_ref(), trunc, method, params)
            .map_err(|e| NodeError::singular(format!("channel {c}: {e}")))?;
        let diff = (&approx.matrix - a).norm_l2();
        let norm = a.norm_l2();
        let mse = diff * diff / (m * n) as f64;
        channels.push(ChannelResult {
            rank: approx.rank,
            psnr: if mse > 0.0 {
                -10.0 * mse.log10()
            } else {
                f64::INFINITY
            },
            rel_error: if norm > 0.0 { diff / norm } else { diff },
            storage_ratio: ((m + n + 1) * approx.rank) as f64 / (m * n) as f64,
            singular_values: approx.singular_values,
        });
        let col = |y: usize| approx.matrix.col(y);
        for (k, p) in out.pixels.iter_mut().enumerate() {
            let v = col(k / n)[k % n] as f32;
            if grayscale {
                p[0] = v;
                p[1] = v;
                p[2] = v;
            } else {
                p[c] = v;
            }
        }
    }
    Ok(Compressed {
        image: out,
        channels,
    })
}

fn declare(b: &mut NodeBuilder) {
    b.doc(
        "Low-rank compression: keeps the k largest singular values of each channel (the \
         best rank-k approximation, Eckart-Young), by faer's SVD or a randomized SVD.",
    );
    b.add_input::<Image>("image");
    b.add_input::<i64>("rank")
        .default(20)
        .min(0.0)
        .doc("k per channel; above min(width, height) it is clamped with a warning.");
    b.add_input::<f64>("energy")
        .default(0.0)
        .range(0.0, 1.0)
        .doc(
            "If > 0, instead of rank: the smallest k whose squared singular values reach this \
         fraction of the channel's squared Frobenius norm.",
        );
    b.add_choice::<Method>("method").doc(
        "full: faer's thin SVD; randomized: Halko, Martinsson & Tropp 2011 (Alg. 4.4 \
         subspace iteration, Alg. 5.1).",
    );
    b.add_input::<i64>("oversample")
        .default(10)
        .range(0.0, 1000.0)
        .doc("Randomized: extra sketch columns p.");
    b.add_input::<i64>("power_iterations")
        .default(2)
        .range(0.0, 100.0)
        .doc("Randomized: subspace iterations q (each re-orthonormalized by QR).");
    b.add_input::<i64>("seed")
        .default(1)
        .min(0.0)
        .doc("Randomized: seed of the Gaussian test matrix.");
    b.add_input::<bool>("grayscale")
        .default(false)
        .doc("Compress the luminance only (one SVD); the output is gray.");
    b.add_output::<Image>("image")
        .doc("The reconstruction; values are not clamped to [0, 1].");
    b.add_output::<Table>("table").doc(
        "One row per channel: channel, rank, psnr (dB, peak 1), rel_error (relative \
         Frobenius), storage_ratio ((m + n + 1) k / (m n)), time_ms (whole node).",
    );
    b.add_output::<Table>("singular_values")
        .doc("One column per channel (r, g, b or gray): the singular values computed.");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let img: Arc<Image> = ctx.input("image")?;
    let rank: i64 = ctx.input("rank")?;
    let energy: f64 = ctx.input("energy")?;
    let method = ctx.choice::<Method>("method")?;
    let params = RandomizedParams {
        oversample: ctx.input::<i64>("oversample")?.max(0) as usize,
        power_iterations: ctx.input::<i64>("power_iterations")?.max(0) as usize,
        seed: ctx.input::<i64>("seed")?.max(0) as u64,
    };
    let grayscale: bool = ctx.input("grayscale")?;
    if !(0.0..=1.0).contains(&energy) {
        return Err(NodeError::invalid("energy", "energy must be in [0, 1]"));
    }
    if rank < 0 {
        return Err(NodeError::invalid("rank", "rank must be at least 0"));
    }
    let size = img.width.min(img.height) as i64;
    let trunc = if energy > 0.0 {
        Truncation::Energy(energy)
    } else {
        if rank > size {
            ctx.log(format!(
                "warning: rank {rank} is larger than min(width, height) = {size}; clamped to {size}"
            ));
        }
        Truncation::Rank(rank.min(size) as usize)
    };
    let t0 = std::time::Instant::now();
    let r = image_svd(&img, trunc, method, params, grayscale)?;
    let millis = t0.elapsed().as_secs_f64() * 1e3;
    let mut table = Table::with_columns(&[
        "channel",
        "rank",
        "psnr",
        "rel_error",
        "storage_ratio",
        "time_ms",
    ]);
    let mut sv = Table::default();
    let names = if grayscale {
        &["gray"][..]
    } else {
        &["r", "g", "b"][..]
    };
    for (c, (ch, name)) in r.channels.iter().zip(names).enumerate() {
        table.push_row(&[
            c as f64,
            ch.rank as f64,
            ch.psnr,
            ch.rel_error,
            ch.storage_ratio,
            millis,
        ]);
        sv.set_column(name, ch.singular_values.clone());
    }
    ctx.set_output("image", r.image);
    ctx.set_output("table", table);
    ctx.set_output("singular_values", sv);
    Ok(())
}

/// Registers `image_svd`.
pub fn register(r: &mut Registry) {
    r.add("image_svd", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::svd::*;
    use super::*;

    const P: RandomizedParams = RandomizedParams {
        oversample: 10,
        power_iterations: 2,
        seed: 7,
    };

    /// A deterministic pseudo-random m x n matrix in [-1, 1].
    fn noise(m: usize, n: usize, seed: u64) -> Mat<f64> {
        let g = randomized::gaussian_matrix(m, n, seed);
        Mat::from_fn(m, n, |i, j| g[(i, j)].tanh())
    }

    #[test]
    fn full_rank_reproduces_the_matrix() {
        for (m, n) in [(40, 25), (25, 40), (30, 30)] {
            let a = noise(m, n, 3);
            let r = low_rank(a.as_ref(), Truncation::Rank(m.min(n)), Method::Full, P).unwrap();
            assert_eq!(r.rank, m.min(n));
            let err = (&r.matrix - &a).norm_max();
            assert!(err < 1e-10, "{m}x{n}: {err}");
            // the singular values are decreasing and their squares sum to ||A||_F^2
            assert!(r.singular_values.windows(2).all(|w| w[0] >= w[1]));
            let s2: f64 = r.singular_values.iter().map(|s| s * s).sum();
            assert!((s2 - frobenius_sq(a.as_ref())).abs() < 1e-9 * s2);
        }
    }

    #[test]
    fn randomized_recovers_an_exact_rank_10_matrix() {
        let (m, n) = (120, 90);
        let a = noise(m, 10, 11) * noise(10, n, 12);
        let r = low_rank(a.as_ref(), Truncation::Rank(10), Method::Randomized, P).unwrap();
        let err = (&r.matrix - &a).norm_l2() / a.norm_l2();
        assert!(err < 1e-8, "{err}");
        // and with no oversampling or power iteration too (the range is exactly rank 10)
        let bare = RandomizedParams {
            oversample: 0,
            power_iterations: 0,
            seed: 1,
        };
        let r = low_rank(a.as_ref(), Truncation::Rank(10), Method::Randomized, bare).unwrap();
        assert!((&r.matrix - &a).norm_l2() / a.norm_l2() < 1e-8);
        // rank 9 of it is not exact: the error is sigma_10 / ||A||_F (Eckart-Young)
        let full = truncated::thin_svd(a.as_ref()).unwrap();
        let r9 = low_rank(a.as_ref(), Truncation::Rank(9), Method::Full, P).unwrap();
        let e9 = (&r9.matrix - &a).norm_l2();
        assert!((e9 - full.s[9]).abs() < 1e-9 * full.s[0]);
    }

    #[test]
    fn energy_picks_the_smallest_rank() {
        // singular values 4, 3, 2, 1: squares 16, 9, 4, 1 of 30
        let s = [4.0, 3.0, 2.0, 1.0];
        assert_eq!(energy_rank(&s, 30.0, 16.0 / 30.0), Some(1));
        assert_eq!(energy_rank(&s, 30.0, 0.54), Some(2));
        assert_eq!(energy_rank(&s, 30.0, 25.0 / 30.0), Some(2));
        assert_eq!(energy_rank(&s, 30.0, 0.9), Some(3));
        assert_eq!(energy_rank(&s, 30.0, 1.0), Some(4));
        assert_eq!(energy_rank(&s[..2], 30.0, 0.9), None);
        // on a matrix, both methods agree with the rule applied to the exact spectrum
        let a = noise(60, 50, 5);
        let f = truncated::thin_svd(a.as_ref()).unwrap();
        let want = energy_rank(&f.s, frobenius_sq(a.as_ref()), 0.8).unwrap();
        let k = |m| {
            low_rank(a.as_ref(), Truncation::Energy(0.8), m, P)
                .unwrap()
                .rank
        };
        assert_eq!(k(Method::Full), want);
        let mut acc = 0.0;
        for v in &f.s[..want - 1] {
            acc += v * v;
        }
        assert!(acc < 0.8 * frobenius_sq(a.as_ref()));
        let kr = k(Method::Randomized);
        assert!(kr.abs_diff(want) <= 1, "randomized {kr}, exact {want}");
    }

    fn picture(w: u32, h: u32) -> Image {
        let mut img = Image::new(w, h, [0.0, 0.0, 0.0, 0.5]);
        for y in 0..h {
            for x in 0..w {
                let (fx, fy) = (x as f32 / w as f32, y as f32 / h as f32);
                img.set(x, y, [fx, fy * fx, (fx * 9.0 + fy * 5.0).sin().abs(), 0.5]);
            }
        }
        img
    }

    #[test]
    fn image_table_values() {
        let img = picture(32, 24);
        let r = image_svd(&img, Truncation::Rank(24), Method::Full, P, false).unwrap();
        for (p, q) in r.image.pixels.iter().zip(&img.pixels) {
            for c in 0..4 {
                assert!((p[c] - q[c]).abs() < 1e-6);
            }
        }
        assert_eq!(r.channels.len(), 3);
        // channel 0 is x / w in every row: exactly rank 1
        let r1 = image_svd(&img, Truncation::Rank(1), Method::Full, P, false).unwrap();
        let ch = &r1.channels[0];
        assert!(ch.rel_error < 1e-12 && ch.psnr > 200.0);
        assert!((ch.storage_ratio - 57.0 / 768.0).abs() < 1e-15);
        let g = image_svd(&img, Truncation::Rank(2), Method::Full, P, true).unwrap();
        assert_eq!(g.channels.len(), 1);
        let p = g.image.get(3, 4);
        assert!(p[0] == p[1] && p[1] == p[2] && p[3] == 0.5);
    }

    #[test]
    fn bad_input_names_the_image() {
        let empty = Image::new(0, 4, [0.0; 4]);
        let e = image_svd(&empty, Truncation::Rank(1), Method::Full, P, false).unwrap_err();
        assert_eq!(e.socket.as_deref(), Some("image"));
        let mut bad = picture(8, 8);
        bad.set(2, 5, [f32::NAN, 0.0, 0.0, 1.0]);
        let e = image_svd(&bad, Truncation::Rank(1), Method::Full, P, false).unwrap_err();
        assert_eq!(e.socket.as_deref(), Some("image"));
        assert!(e.message.contains("(2, 5)"), "{}", e.message);
    }
}
