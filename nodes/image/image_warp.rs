//! `image_warp`: warps an image so that source control points move to target points, by IDW,
//! RBF or MLS (the algorithms are in `warp/`; this file reads the sockets).

use super::warp::{self, Fill, Kernel, Mapping, Method, Side, WarpError, WarpParams};
use cgnodes_api::prelude::*;
use std::path::Path;

/// Source and target control points.
pub type PointPairs = (Vec<[f64; 2]>, Vec<[f64; 2]>);

/// Why CSV text is not a list of control points (`read_points_csv`).
#[derive(Debug, thiserror::Error)]
pub enum PointsCsvError {
    /// The CSV reader refused the text.
    #[error("{0}")]
    Csv(crate::BoxedError),
    /// No header line.
    #[error("the file is empty")]
    Empty,
    /// The header lacks one of `sx`, `sy`, `tx`, `ty`.
    #[error("no column '{name}' (the header needs sx,sy,tx,ty)")]
    MissingColumn { name: &'static str },
    /// A cell of row `row` (the header is row 1) does not parse as a number.
    #[error("row {row}: '{text}' is not a number")]
    NotANumber { row: usize, text: String },
}

/// Control points from CSV text with a header naming columns `sx,sy,tx,ty` (any order,
/// other columns ignored, `#` comments allowed): (source points, target points).
pub fn read_points_csv(text: &str) -> Result<PointPairs, PointsCsvError> {
    let rows = cgnodes_api::io::csv::read(text, true, true)
        .map_err(|e| PointsCsvError::Csv(e.into()))?
        .ok_or(PointsCsvError::Empty)?;
    let mut cols = [0usize; 4];
    for (c, name) in cols.iter_mut().zip(["sx", "sy", "tx", "ty"]) {
        *c = rows
            .column(name)
            .ok_or(PointsCsvError::MissingColumn { name })?;
    }
    let (mut p, mut q) = (Vec::new(), Vec::new());
    for (r, row) in rows.rows.iter().enumerate() {
        let mut v = [0.0; 4];
        for (x, &c) in v.iter_mut().zip(&cols) {
            let s = row.get(c).map(String::as_str).unwrap_or("");
            *x = s.parse().map_err(|_| PointsCsvError::NotANumber {
                row: r + 2,
                text: s.to_string(),
            })?;
        }
        p.push([v[0], v[1]]);
        q.push([v[2], v[3]]);
    }
    Ok((p, q))
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Warps an image by control points: IDW, RBF or MLS; inverse or forward mapping.");
    b.add_input::<Image>("image");
    b.add_input::<Vec<[f64; 2]>>("source_points")
        .optional()
        .doc("Control points p_i in pixels (origin at the top-left corner, y down).");
    b.add_input::<Vec<[f64; 2]>>("target_points")
        .optional()
        .doc("Where each p_i goes (q_i), as many as source_points.");
    b.add_input::<String>("points_file")
        .optional()
        .file_in()
        .doc("CSV with columns sx,sy,tx,ty, instead of the two lists.");
    b.add_choice::<Method>("method")
        .doc("idw, rbf (with affine part), mls_affine, mls_similarity, mls_rigid.");
    let d = WarpParams::default();
    b.add_input::<f64>("mu")
        .default(d.mu)
        .range(1e-3, 64.0)
        .doc("IDW exponent: weights 1 / |x - p_i|^mu.");
    b.add_choice::<Kernel>("kernel").doc("RBF kernel.");
    b.add_input::<f64>("radius")
        .default(d.radius)
        .min(0.0)
        .doc("RBF radius in pixels; 0 = each centre's distance to its nearest other centre.");
    b.add_input::<f64>("alpha")
        .default(d.alpha)
        .range(1e-3, 32.0)
        .doc("MLS weight exponent: weights 1 / |p_i - v|^(2 alpha).");
    b.add_choice::<Mapping>("mapping")
        .doc("inverse: sample the source at g(y), g(q_i) = p_i; forward: move pixels by f.");
    b.add_choice::<Fill>("fill")
        .doc("Forward mapping's holes: none, nearest, push_pull.");
    b.add_input::<i64>("grid")
        .default(0)
        .range(0.0, 4096.0)
        .doc("0 = evaluate the map at every pixel; N = on an N-pixel grid, bilinear between.");
    b.add_input::<bool>("measure_grid").default(false).doc(
        "Also report map_error: the largest distance (px) of the grid map from the exact one.",
    );
    b.add_output::<Image>("image");
    b.add_output::<Image>("holes")
        .doc("White where forward mapping left a hole (before filling).");
    b.add_output::<Table>("table").doc(
        "residual (max |f(p_i) - q_i|, px), holes, filled, outside (pixels), time (s), \
         map_error (px, with measure_grid).",
    );
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let t0 = std::time::Instant::now();
    let img: Arc<Image> = ctx.input("image")?;
    let lists = (
        ctx.input_opt::<Vec<[f64; 2]>>("source_points")?,
        ctx.input_opt::<Vec<[f64; 2]>>("target_points")?,
    );
    let file: Option<String> = ctx.input_opt("points_file")?;
    let from_file = file.is_some();
    let (p, q) =
        match (file, lists) {
            (Some(_), (Some(_), _) | (_, Some(_))) => {
                return Err(NodeError::invalid(
                    "points_file",
                    "give either points_file or source_points and target_points, not both",
                ))
            }
            (Some(f), _) => {
                let path = ctx.input_path(&f);
                let text = std::fs::read_to_string(&path)
                    .map_err(|e| NodeError::io(&path, e).at("points_file"))?;
                read_points_csv(&text).map_err(|e| {
                    // Only files of the run's own folders are quoted (issue 23).
                    let e = if ctx.files().is_within_run_folders(&path) {
                        e.to_string()
                    } else {
                        "not a CSV with numeric columns sx,sy,tx,ty".into()
                    };
                    NodeError::invalid("points_file", format!("{}: {e}", Path::new(&f).display()))
                })?
            }
            (None, (Some(p), Some(q))) => (p, q),
            (None, (None, _)) => return Err(NodeError::invalid(
                "source_points",
                "no control points: connect source_points and target_points or give points_file",
            )),
            (None, (Some(_), None)) => {
                return Err(NodeError::invalid(
                    "target_points",
                    "source_points are given but target_points are not",
                ))
            }
        };
    let params = WarpParams {
        method: ctx.choice("method")?,
        mu: ctx.input("mu")?,
        kernel: ctx.choice("kernel")?,
        radius: ctx.input("radius")?,
        alpha: ctx.input("alpha")?,
    };
    for (name, v, lo) in [("mu", params.mu, 0.0), ("alpha", params.alpha, 0.0)] {
        if !(v.is_finite() && v > lo) {
            return Err(NodeError::invalid(name, "must be a positive number"));
        }
    }
    if !(params.radius.is_finite() && params.radius >= 0.0) {
        return Err(NodeError::invalid("radius", "must be >= 0"));
    }
    let mapping: Mapping = ctx.choice("mapping")?;
    let fill: Fill = ctx.choice("fill")?;
    let grid: i64 = ctx.input("grid")?;
    let grid = u32::try_from(grid).map_err(|_| NodeError::invalid("grid", "must be >= 0"))?;
    let r = warp::warp_image(&img, &p, &q, &params, mapping, fill, grid)
        .map_err(|e| warp_error(&e, mapping, from_file))?;
    let secs = t0.elapsed().as_secs_f64();
    let mut table = Table::from_row(&[
        ("residual", r.residual),
        ("holes", r.hole_count as f64),
        ("filled", r.filled as f64),
        ("outside", r.outside as f64),
        ("time", secs),
    ]);
    if ctx.input::<bool>("measure_grid")? {
        // Measured after `time`: the exact map costs what the grid saves.
        let (from, to) = match mapping {
            Mapping::Inverse => (&q, &p),
            Mapping::Forward => (&p, &q),
        };
        let map = warp::fit(&params, from, to).map_err(|e| warp_error(&e, mapping, from_file))?;
        let err = warp::grid_error(map.as_ref(), img.width, img.height, grid);
        table.set_column("map_error", vec![err]);
    }
    ctx.set_output("image", r.image);
    ctx.set_output("holes", r.holes);
    ctx.set_output("table", table);
    Ok(())
}

/// The node error of a fit error: the socket is the user's list at fault (for inverse
/// mapping the fit runs from the target points to the source points), or `points_file`. Too
/// few points is blamed on `source_points`, different counts on `target_points`.
fn warp_error(e: &WarpError, mapping: Mapping, from_file: bool) -> NodeError {
    let user_side = match (e, mapping) {
        (WarpError::Mismatch { .. }, _) => Side::To,
        (WarpError::TooFew { .. }, _) => Side::From,
        (_, Mapping::Forward) => e.side(),
        (_, Mapping::Inverse) => match e.side() {
            Side::From => Side::To,
            Side::To => Side::From,
        },
    };
    let socket = match (from_file, user_side) {
        (true, _) => "points_file",
        (false, Side::From) => "source_points",
        (false, Side::To) => "target_points",
    };
    match e {
        WarpError::Singular(_) => NodeError::singular(e.to_string()).at(socket),
        _ => NodeError::invalid(socket, e.to_string()),
    }
}

/// Registers `image_warp`.
pub fn register(r: &mut Registry) {
    r.add("image_warp", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_csv_reads_named_columns_and_refuses_bad_rows() {
        let (p, q) = read_points_csv("# pairs\nsx,sy,tx,ty\n1,2,3,4\n5, 6 ,7,8\n").unwrap();
        assert_eq!(p, vec![[1.0, 2.0], [5.0, 6.0]]);
        assert_eq!(q, vec![[3.0, 4.0], [7.0, 8.0]]);
        let (p, _) = read_points_csv("ty,tx,sy,sx\n1,2,3,4\n").unwrap();
        assert_eq!(p, vec![[4.0, 3.0]]);
        assert!(read_points_csv("sx,sy,tx\n1,2,3\n")
            .unwrap_err()
            .to_string()
            .contains("'ty'"));
        assert!(read_points_csv("sx,sy,tx,ty\n1,2,x,4\n")
            .unwrap_err()
            .to_string()
            .contains("row 2"));
        assert!(read_points_csv("").is_err());
    }

    #[test]
    fn errors_name_the_users_list_for_both_mappings() {
        let e = WarpError::Coincident { i: 0, j: 1 };
        assert_eq!(
            warp_error(&e, Mapping::Forward, false).socket.as_deref(),
            Some("source_points")
        );
        assert_eq!(
            warp_error(&e, Mapping::Inverse, false).socket.as_deref(),
            Some("target_points")
        );
        let e = WarpError::Singular("x".into());
        let n = warp_error(&e, Mapping::Forward, true);
        assert_eq!(n.socket.as_deref(), Some("points_file"));
        assert_eq!(n.kind, ErrorKind::Singular);
    }
}
