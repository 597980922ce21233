//! `rpca`: Robust PCA (the course's §3.2 restoration task): a matrix or each channel of an
//! image split into a low-rank part and a sparse part by ADMM (`rpca/admm.rs`); this file
//! reads the sockets, the CSV matrix and the channels.

#[path = "rpca/admm.rs"]
pub mod admm;
#[path = "rpca/svt.rs"]
pub mod svt;

use admm::{Decomposition, Params};
use cgnodes_api::prelude::*;
use faer::Mat;

/// Why CSV text is not a matrix (`parse_matrix_csv`); rows and columns count from 1.
#[derive(Debug, thiserror::Error)]
pub enum MatrixCsvError {
    /// The CSV reader refused the text.
    #[error("{0}")]
    Csv(crate::BoxedError),
    /// Nothing but blank lines and comments.
    #[error("the file has no rows")]
    NoRows,
    /// A row is longer or shorter than the first.
    #[error("row {row} has {len} numbers but row 1 has {first} (rows must be equally long)")]
    Ragged {
        row: usize,
        len: usize,
        first: usize,
    },
    /// A cell does not parse as a number.
    #[error("row {row}, column {column}: '{text}' is not a number")]
    NotANumber {
        row: usize,
        column: usize,
        text: String,
    },
    /// A cell is NaN or infinite.
    #[error("row {row}, column {column}: '{text}' is not finite")]
    NotFinite {
        row: usize,
        column: usize,
        text: String,
    },
}

/// A matrix from CSV text: every row a list of numbers (no header; blank lines and `#`
/// comments skipped). Errors say which row and column.
pub fn parse_matrix_csv(text: &str) -> Result<Mat<f64>, MatrixCsvError> {
    let rows = cgnodes_api::io::csv::read(text, true, true)
        .map_err(|e| MatrixCsvError::Csv(e.into()))?
        .ok_or(MatrixCsvError::NoRows)?;
    let all: Vec<&Vec<String>> = std::iter::once(&rows.header).chain(&rows.rows).collect();
    let n = all[0].len();
    let mut values = Vec::with_capacity(all.len() * n);
    for (r, row) in all.iter().enumerate() {
        if row.len() != n {
            return Err(MatrixCsvError::Ragged {
                row: r + 1,
                len: row.len(),
                first: n,
            });
        }
        for (c, s) in row.iter().enumerate() {
            let v: f64 = s.parse().map_err(|_| MatrixCsvError::NotANumber {
                row: r + 1,
                column: c + 1,
                text: s.clone(),
            })?;
            if !v.is_finite() {
                return Err(MatrixCsvError::NotFinite {
                    row: r + 1,
                    column: c + 1,
                    text: s.clone(),
                });
            }
            values.push(v);
        }
    }
    Ok(Mat::from_fn(all.len(), n, |i, j| values[i * n + j]))
}

/// The RGB channel matrices of `img`, transposed (width x height: the column-major matrix
/// walks the row-major pixels in order; RPCA of M^T is RPCA of M transposed, λ and ρ alike);
/// one when the image is gray
/// (R = G = B everywhere), since the three decompositions would be equal.
pub fn image_channels(img: &Image) -> Result<Vec<Mat<f64>>, NodeError> {
    let (w, h) = (img.width as usize, img.height as usize);
    if w == 0 || h == 0 {
        return Err(NodeError::invalid("image", "the image is empty"));
    }
    if let Some(i) = img
        .pixels
        .iter()
        .position(|p| p.iter().any(|v| !v.is_finite()))
    {
        return Err(NodeError::invalid(
            "image",
            format!("pixel ({}, {}) is not finite", i % w, i / w),
        ));
    }
    let gray = img.pixels.iter().all(|p| p[0] == p[1] && p[1] == p[2]);
    let count = if gray { 1 } else { 3 };
    Ok((0..count)
        .map(|c| Mat::from_fn(w, h, |x, y| img.pixels[y * w + x][c] as f64))
        .collect())
}

/// An image of the transposed channel matrices (`image_channels`' layout; one matrix:
/// gray), alpha 1.
pub fn to_image(channels: &[Mat<f64>]) -> Image {
    let (w, h) = channels[0].shape();
    let mut img = Image::new(w as u32, h as u32, [0.0, 0.0, 0.0, 1.0]);
    for (k, p) in img.pixels.iter_mut().enumerate() {
        for (c, v) in p.iter_mut().take(3).enumerate() {
            *v = channels[c.min(channels.len() - 1)][(k % w, k / w)] as f32;
        }
    }
    img
}

/// A matrix as an image (gray), for a CSV input: row i of the matrix is row i of the image.
pub fn matrix_image(m: &Mat<f64>) -> Image {
    to_image(&[m.transpose().to_owned()])
}

/// A matrix as a table: columns c1, c2, ...
pub fn to_table(m: &Mat<f64>) -> Table {
    let mut t = Table::default();
    for j in 0..m.ncols() {
        t.set_column(
            &format!("c{}", j + 1),
            (0..m.nrows()).map(|i| m[(i, j)]).collect(),
        );
    }
    t
}

/// Decomposes each matrix; errors name no socket (an SVD failure).
pub fn decompose_all(mats: &[Mat<f64>], p: Params) -> Result<Vec<Decomposition>, NodeError> {
    mats.iter()
        .map(|m| admm::rpca(m.as_ref(), p).map_err(|e| NodeError::singular(e.to_string())))
        .collect()
}

fn declare(b: &mut NodeBuilder) {
    b.doc(
        "Robust PCA (Candès et al. 2011) by ADMM: splits an image's channels, or a CSV \
         matrix, into a low-rank part and a sparse part (outliers, salt-and-pepper noise).",
    );
    b.add_input::<Image>("image")
        .optional()
        .doc("Each channel a matrix (one for a gray image).");
    b.add_input::<String>("matrix")
        .optional()
        .file_in()
        .doc("Instead of image: a CSV of numbers, one matrix row per line, no header.");
    b.add_input::<f64>("lambda")
        .default(0.0)
        .min(0.0)
        .doc("Weight of ||S||_1; 0 = 1 / sqrt(max(m, n)).");
    b.add_input::<f64>("rho")
        .default(0.0)
        .min(0.0)
        .doc("ADMM penalty; 0 = m n / (4 ||M||_1) (Candès et al. §5).");
    b.add_input::<f64>("tolerance")
        .default(1e-7)
        .range(1e-15, 1.0)
        .doc("Stop when the primal and dual residuals (relative to ||M||_F) are below it.");
    b.add_input::<i64>("max_iterations")
        .default(1000)
        .range(1.0, 1e6);
    b.add_output::<Image>("low_rank")
        .doc("L as an image (gray for a matrix input).");
    b.add_output::<Image>("sparse")
        .doc("S as an image (signed values; gray for a matrix input).");
    b.add_output::<Table>("low_rank_matrix")
        .doc("L as a table (columns c1..cn) for a matrix input; empty for an image.");
    b.add_output::<Table>("sparse_matrix")
        .doc("S as a table for a matrix input; empty for an image.");
    b.add_output::<Table>("log").doc(
        "One row per iteration and channel: channel, iteration, primal, dual, rank (of L), \
         nonzeros (of S), time_ms (since the channel's start).",
    );
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let img: Option<Arc<Image>> = ctx.input_opt("image")?;
    let file: Option<String> = ctx.input_opt("matrix")?;
    let p = Params {
        lambda: ctx.input("lambda")?,
        rho: ctx.input("rho")?,
        tolerance: ctx.input("tolerance")?,
        max_iterations: ctx.input::<i64>("max_iterations")?.max(1) as usize,
    };
    let (mats, from_matrix) = match (img, file) {
        (Some(_), Some(_)) => {
            return Err(NodeError::invalid(
                "matrix",
                "give either image or matrix, not both",
            ))
        }
        (None, None) => {
            return Err(NodeError::invalid(
                "image",
                "connect an image or give a matrix file",
            ))
        }
        (Some(img), None) => (image_channels(&img)?, false),
        (None, Some(f)) => {
            let path = ctx.input_path(&f);
            let text =
                std::fs::read_to_string(&path).map_err(|e| NodeError::io(&path, e).at("matrix"))?;
            let m =
                parse_matrix_csv(&text).map_err(|e| NodeError::invalid("matrix", e.to_string()))?;
            (vec![m], true)
        }
    };
    let res = decompose_all(&mats, p)?;
    let mut log = Table::with_columns(&[
        "channel",
        "iteration",
        "primal",
        "dual",
        "rank",
        "nonzeros",
        "warm",
        "time_ms",
    ]);
    for (c, d) in res.iter().enumerate() {
        for (k, s) in d.log.iter().enumerate() {
            log.push_row(&[
                c as f64,
                (k + 1) as f64,
                s.primal,
                s.dual,
                s.rank as f64,
                s.nonzeros as f64,
                f64::from(u8::from(s.warm)),
                s.seconds * 1e3,
            ]);
        }
        if !d.converged {
            let last = d.log.last().copied();
            let (pr, du) = last.map_or((f64::NAN, f64::NAN), |s| (s.primal, s.dual));
            ctx.log(format!(
                "warning: channel {c} did not converge in {} iterations: primal residual {pr:.3e}, \
                 dual residual {du:.3e} (tolerance {:.1e})",
                p.max_iterations, p.tolerance
            ));
        }
    }
    if let Some(d) = res.first() {
        log.meta.insert("lambda".into(), format!("{}", d.lambda));
        log.meta.insert("rho".into(), format!("{}", d.rho));
    }
    let lows: Vec<Mat<f64>> = res.iter().map(|d| d.low_rank.clone()).collect();
    let sparses: Vec<Mat<f64>> = res.iter().map(|d| d.sparse.clone()).collect();
    let (lt, st) = if from_matrix {
        (to_table(&lows[0]), to_table(&sparses[0]))
    } else {
        (Table::default(), Table::default())
    };
    if from_matrix {
        ctx.set_output("low_rank", matrix_image(&lows[0]));
        ctx.set_output("sparse", matrix_image(&sparses[0]));
    } else {
        ctx.set_output("low_rank", to_image(&lows));
        ctx.set_output("sparse", to_image(&sparses));
    }
    ctx.set_output("low_rank_matrix", lt);
    ctx.set_output("sparse_matrix", st);
    ctx.set_output("log", log);
    Ok(())
}

/// Registers `rpca`.
pub fn register(r: &mut Registry) {
    r.add("rpca", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::admm::*;
    use super::*;
    use crate::image_svd::svd::randomized::gaussian_matrix;

    /// Candès et al. §4.1's synthetic case: L = X Y^T / sqrt(n) with Gaussian X (n x r) and
    /// Y, and a fraction `frac` of entries corrupted by values uniform in [-50, 50].
    pub fn synthetic(n: usize, r: usize, frac: f64, seed: u64) -> (Mat<f64>, Mat<f64>) {
        let l = gaussian_matrix(n, r, seed) * gaussian_matrix(r, n, seed + 1).as_ref();
        let l = Mat::from_fn(n, n, |i, j| l[(i, j)] / (n as f64).sqrt());
        let u = gaussian_matrix(n, 2 * n, seed + 2);
        // the Gaussian's CDF by erf is not in std: use the sign and fraction of two normals
        // as uniform draws instead, through the normal's tail probability of |g| (monotone)
        let unif = |g: f64| {
            let x = g.abs();
            // Abramowitz & Stegun 7.1.26: erf to 1.5e-7, enough to pick positions and values
            let t = 1.0 / (1.0 + 0.3275911 * x / 2f64.sqrt());
            let poly = t
                * (0.254829592
                    + t * (-0.284496736
                        + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
            1.0 - poly * (-x * x / 2.0).exp()
        };
        let s = Mat::from_fn(n, n, |i, j| {
            if unif(u[(i, j)]) < frac {
                50.0 * unif(u[(i, n + j)]) * u[(i, n + j)].signum()
            } else {
                0.0
            }
        });
        (l, s)
    }

    fn recovers(n: usize, r: usize) {
        let (l0, s0) = synthetic(n, r, 0.05, 3);
        let m = &l0 + &s0;
        let p = Params {
            lambda: 0.0,
            rho: 0.0,
            tolerance: 1e-9,
            max_iterations: 500,
        };
        let d = rpca(m.as_ref(), p).unwrap();
        assert!(d.converged, "{:?}", d.log.last());
        let el = (&d.low_rank - &l0).norm_l2() / l0.norm_l2();
        let es = (&d.sparse - &s0).norm_l2() / s0.norm_l2();
        assert!(
            el < 1e-6 && es < 1e-6,
            "L {el:e}, S {es:e}, {} iterations",
            d.log.len()
        );
        assert_eq!(d.log.last().unwrap().rank, r);
        // the low-rank phase runs on the warm-started thresholding, so the recovery covers it
        assert!(d.log.last().unwrap().warm, "last step not warm-started");
        assert!((d.lambda - 1.0 / (n as f64).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn recovers_the_candes_synthetic_case_200() {
        recovers(200, 10);
    }

    /// The 500 x 500, rank 25 case (about 60 SVDs of 500 x 500, about 10 s).
    #[test]
    fn recovers_the_candes_synthetic_case_500() {
        recovers(500, 25);
    }

    #[test]
    fn thresholds_are_the_proximal_operators() {
        assert_eq!(shrink(3.0, 1.0), 2.0);
        assert_eq!(shrink(-3.0, 1.0), -2.0);
        assert_eq!(shrink(0.5, 1.0), 0.0);
        // SVT of diag(5, 2, 0.5) with tau 1: diag(4, 1, 0), rank 2
        let x = Mat::from_fn(3, 3, |i, j| if i == j { [5.0, 2.0, 0.5][i] } else { 0.0 });
        let (l, k) = singular_value_threshold(x.as_ref(), 1.0).unwrap();
        assert_eq!(k, 2);
        let want = Mat::from_fn(3, 3, |i, j| if i == j { [4.0, 1.0, 0.0][i] } else { 0.0 });
        assert!((&l - &want).norm_max() < 1e-12);
    }

    #[test]
    fn non_convergence_is_reported() {
        let (l0, s0) = synthetic(40, 3, 0.05, 5);
        let m = &l0 + &s0;
        let p = Params {
            lambda: 0.0,
            rho: 0.0,
            tolerance: 1e-12,
            max_iterations: 3,
        };
        let d = rpca(m.as_ref(), p).unwrap();
        assert!(!d.converged);
        assert_eq!(d.log.len(), 3);
        // the last primal residual is ||M - L - S||_F / ||M||_F
        let r = (&m - &d.low_rank - &d.sparse).norm_l2() / m.norm_l2();
        assert!((d.log[2].primal - r).abs() < 1e-12);
    }

    #[test]
    fn csv_matrices_and_their_errors() {
        let m = parse_matrix_csv("# a 2x3 matrix\n1, 2, 3\n\n4,5,6.5\n").unwrap();
        assert_eq!(m.shape(), (2, 3));
        assert_eq!(m[(1, 2)], 6.5);
        let e = parse_matrix_csv("1,2,3\n4,5\n").unwrap_err().to_string();
        assert!(e.contains("row 2 has 2 numbers but row 1 has 3"), "{e}");
        let e = parse_matrix_csv("1,2\nNaN,5\n").unwrap_err().to_string();
        assert!(
            e.contains("row 2, column 1") && e.contains("not finite"),
            "{e}"
        );
        let e = parse_matrix_csv("1,x\n").unwrap_err().to_string();
        assert!(e.contains("'x' is not a number"), "{e}");
        assert!(parse_matrix_csv("\n").is_err());
    }

    #[test]
    fn images_split_by_channel() {
        let mut img = Image::new(6, 4, [0.2, 0.2, 0.2, 1.0]);
        assert_eq!(image_channels(&img).unwrap().len(), 1);
        img.set(1, 2, [0.9, 0.1, 0.2, 1.0]);
        let ch = image_channels(&img).unwrap();
        assert_eq!(ch.len(), 3);
        assert_eq!(ch[0][(1, 2)], 0.9f32 as f64);
        assert_eq!(to_image(&ch), img);
        img.set(0, 3, [f32::NAN, 0.0, 0.0, 1.0]);
        let e = image_channels(&img).unwrap_err();
        assert_eq!(e.socket.as_deref(), Some("image"));
        assert!(e.message.contains("(0, 3)"));
        let e = image_channels(&Image::new(0, 0, [0.0; 4])).unwrap_err();
        assert_eq!(e.socket.as_deref(), Some("image"));
    }
}
