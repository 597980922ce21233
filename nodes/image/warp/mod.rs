//! Image warping by scattered control points (the course's homework 1, study book §2.1):
//! maps f with f(p_i) = q_i fitted by inverse distance weighting (`idw`), radial basis
//! functions with an affine part (`rbf`) or moving least squares (`mls`), and their
//! application to an image (`apply`, `fill`).
//!
//! Coordinates are pixel units with the origin at the top-left corner of the top-left pixel,
//! x right, y down (the centre of pixel (i, j) is (i + 0.5, j + 0.5)), as in
//! `Image::sample_bilinear`.

pub mod apply;
pub mod fill;
pub mod idw;
pub mod mls;
pub mod rbf;

pub use apply::{Fill, Mapping};
use cgnodes_api::node::Choice;
use cgnodes_api::types::Image;
pub use rbf::Kernel;

/// A fitted map of the plane: the warp evaluated at one point.
pub trait WarpMap: Sync {
    /// f(x).
    fn eval(&self, x: [f64; 2]) -> [f64; 2];
}

/// Runs `f` with this thread's scratch vector for per-point weights (cleared), so that
/// evaluating a map at every pixel does not allocate per pixel.
pub(crate) fn with_weights<R>(f: impl FnOnce(&mut Vec<f64>) -> R) -> R {
    thread_local! {
        static WEIGHTS: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
    }
    WEIGHTS.with_borrow_mut(|w| {
        w.clear();
        f(w)
    })
}

/// Which method fits the map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Shepard's inverse distance weighting with locally fitted linear maps.
    Idw,
    /// Radial basis functions plus an affine part.
    Rbf,
    /// Moving least squares, affine.
    MlsAffine,
    /// Moving least squares, similarity.
    MlsSimilarity,
    /// Moving least squares, rigid.
    MlsRigid,
}

impl Choice for Method {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("idw", Method::Idw),
        ("rbf", Method::Rbf),
        ("mls_affine", Method::MlsAffine),
        ("mls_similarity", Method::MlsSimilarity),
        ("mls_rigid", Method::MlsRigid),
    ];
}

impl Method {
    /// The fewest control points the method can fit: an affine part needs three points not
    /// on a line, a similarity or rotation two.
    pub fn min_points(self) -> usize {
        match self {
            Method::Idw => 1,
            Method::Rbf | Method::MlsAffine => 3,
            Method::MlsSimilarity | Method::MlsRigid => 2,
        }
    }

    /// Whether the method needs control points that are not all on one line.
    fn needs_spread(self) -> bool {
        matches!(self, Method::Rbf | Method::MlsAffine)
    }
}

/// Every parameter of a fit.
#[derive(Clone, Copy, Debug)]
pub struct WarpParams {
    /// The method.
    pub method: Method,
    /// IDW exponent mu of the weights 1 / |x - p_i|^mu.
    pub mu: f64,
    /// RBF kernel.
    pub kernel: Kernel,
    /// RBF radius; 0 = each centre's distance to its nearest other centre.
    pub radius: f64,
    /// MLS weight exponent alpha of the weights 1 / |p_i - v|^(2 alpha).
    pub alpha: f64,
}

impl Default for WarpParams {
    fn default() -> Self {
        WarpParams {
            method: Method::Idw,
            mu: 2.0,
            kernel: Kernel::ThinPlate,
            radius: 0.0,
            alpha: 1.0,
        }
    }
}

/// Which list of control points an error is about: the points the map starts from (its
/// domain) or the points they go to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// The points p_i with f(p_i) = q_i.
    From,
    /// The points q_i.
    To,
}

/// Why a map cannot be fitted.
#[derive(Clone, Debug, PartialEq)]
pub enum WarpError {
    /// The two lists have different lengths.
    Mismatch { from: usize, to: usize },
    /// Fewer points than the method needs.
    TooFew { need: usize, got: usize },
    /// A coordinate is NaN or infinite.
    NotFinite { side: Side, index: usize },
    /// Two points of the domain coincide.
    Coincident { i: usize, j: usize },
    /// All points lie on one line, which leaves the affine part undetermined.
    Collinear,
    /// The linear system of the fit is singular (or too ill-conditioned to interpolate).
    Singular(String),
}

impl WarpError {
    /// The fitted map's list at fault (a count mismatch is blamed on the second list).
    pub fn side(&self) -> Side {
        match self {
            WarpError::Mismatch { .. } => Side::To,
            WarpError::NotFinite { side, .. } => *side,
            _ => Side::From,
        }
    }
}

impl std::fmt::Display for WarpError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            WarpError::Mismatch { from, to } => write!(
                f,
                "{to} target points for {from} source points: the counts must be equal"
            ),
            WarpError::TooFew { need, got } => {
                write!(f, "{got} control points, the method needs at least {need}")
            }
            WarpError::NotFinite { index, .. } => {
                write!(f, "point {index} has a NaN or infinite coordinate")
            }
            WarpError::Coincident { i, j } => write!(
                f,
                "control points {i} and {j} coincide: the map cannot send one point to two \
                 (for rbf the system is singular)"
            ),
            WarpError::Collinear => write!(
                f,
                "all control points lie on one line: the affine part is undetermined"
            ),
            WarpError::Singular(m) => write!(f, "singular system: {m}"),
        }
    }
}

/// Checks the control points for `method` (counts, finiteness, coincidence, spread).
pub fn check_points(method: Method, from: &[[f64; 2]], to: &[[f64; 2]]) -> Result<(), WarpError> {
    if from.len() != to.len() {
        return Err(WarpError::Mismatch {
            from: from.len(),
            to: to.len(),
        });
    }
    for (side, pts) in [(Side::From, from), (Side::To, to)] {
        if let Some(index) = pts
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(WarpError::NotFinite { side, index });
        }
    }
    if from.len() < method.min_points() {
        return Err(WarpError::TooFew {
            need: method.min_points(),
            got: from.len(),
        });
    }
    for i in 0..from.len() {
        for j in i + 1..from.len() {
            if from[i] == from[j] {
                return Err(WarpError::Coincident { i, j });
            }
        }
    }
    if method.needs_spread() && collinear(from) {
        return Err(WarpError::Collinear);
    }
    Ok(())
}

/// Whether the points lie on one line, to a relative tolerance: the smaller eigenvalue of
/// their covariance is below 1e-12 of the larger.
pub fn collinear(p: &[[f64; 2]]) -> bool {
    let n = p.len() as f64;
    let c = p
        .iter()
        .fold([0.0; 2], |a, x| [a[0] + x[0] / n, a[1] + x[1] / n]);
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for x in p {
        let (dx, dy) = (x[0] - c[0], x[1] - c[1]);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    let tr = sxx + syy;
    let det = sxx * syy - sxy * sxy;
    // For a 2x2 SPD matrix, det / tr^2 ~ lambda_min / lambda_max.
    det <= 1e-12 * tr * tr
}

/// Fits the map f with f(from_i) = to_i by `params.method`.
pub fn fit(
    params: &WarpParams,
    from: &[[f64; 2]],
    to: &[[f64; 2]],
) -> Result<Box<dyn WarpMap>, WarpError> {
    check_points(params.method, from, to)?;
    Ok(match params.method {
        Method::Idw => Box::new(idw::Idw::fit(from, to, params.mu)),
        Method::Rbf => Box::new(rbf::Rbf::fit(from, to, params.kernel, params.radius)?),
        Method::MlsAffine => Box::new(mls::Mls::new(from, to, mls::MlsKind::Affine, params.alpha)),
        Method::MlsSimilarity => Box::new(mls::Mls::new(
            from,
            to,
            mls::MlsKind::Similarity,
            params.alpha,
        )),
        Method::MlsRigid => Box::new(mls::Mls::new(from, to, mls::MlsKind::Rigid, params.alpha)),
    })
}

/// The largest |f(from_i) - to_i|: how far the fitted map is from interpolating.
pub fn residual(map: &dyn WarpMap, from: &[[f64; 2]], to: &[[f64; 2]]) -> f64 {
    from.iter()
        .zip(to)
        .map(|(p, q)| {
            let y = map.eval(*p);
            (y[0] - q[0]).hypot(y[1] - q[1])
        })
        .fold(0.0, f64::max)
}

/// What `warp_image` returns.
#[derive(Clone, Debug)]
pub struct WarpResult {
    /// The warped image, the size of the input.
    pub image: Image,
    /// Opaque white where nothing mapped to (forward mapping), opaque black elsewhere.
    pub holes: Image,
    /// Largest |f(p_i) - q_i| of the fitted map (for inverse mapping, of g: |g(q_i) - p_i|).
    pub residual: f64,
    /// Pixels nothing mapped to (forward mapping).
    pub hole_count: usize,
    /// Holes the fill gave a colour.
    pub filled: usize,
    /// Output pixels whose preimage lies outside the source (inverse mapping).
    pub outside: usize,
}

/// Warps `src` so that source points `p` move to target points `q`: inverse mapping fits g
/// with g(q_i) = p_i and samples the source at g of each output pixel centre; forward mapping
/// fits f with f(p_i) = q_i and moves each source pixel to the pixel under f(centre), then
/// fills the holes by `fill`. `grid` > 0 evaluates the map only every `grid` pixels and
/// interpolates it bilinearly in between.
pub fn warp_image(
    src: &Image,
    p: &[[f64; 2]],
    q: &[[f64; 2]],
    params: &WarpParams,
    mapping: Mapping,
    fill: Fill,
    grid: u32,
) -> Result<WarpResult, WarpError> {
    let (from, to) = match mapping {
        Mapping::Inverse => (q, p),
        Mapping::Forward => (p, q),
    };
    if p.len() != q.len() {
        return Err(WarpError::Mismatch {
            from: p.len(),
            to: q.len(),
        });
    }
    // Other errors are about the fit's lists (`from`, `to`): for inverse mapping `from` is q.
    let map = fit(params, from, to)?;
    let residual = residual(map.as_ref(), from, to);
    let field = apply::eval_field(map.as_ref(), src.width, src.height, grid);
    let (w, h) = (src.width, src.height);
    Ok(match mapping {
        Mapping::Inverse => {
            let (image, outside) = apply::warp_inverse(src, &field);
            WarpResult {
                image,
                holes: fill::holes_image(w, h, &[]),
                residual,
                hole_count: 0,
                filled: 0,
                outside,
            }
        }
        Mapping::Forward => {
            let (mut image, holes) = apply::warp_forward(src, &field);
            let hole_count = holes.iter().filter(|&&b| b).count();
            let filled = fill::fill_holes(&mut image, &holes, fill);
            WarpResult {
                holes: fill::holes_image(w, h, &holes),
                image,
                residual,
                hole_count,
                filled,
                outside: 0,
            }
        }
    })
}

/// The largest distance (px) between `map` evaluated on a `grid`-pixel grid and interpolated
/// (`apply::eval_field`) and `map` evaluated at every pixel centre of a `w` x `h` image: what
/// `grid` costs in accuracy. 0 for `grid` = 0.
pub fn grid_error(map: &dyn WarpMap, w: u32, h: u32, grid: u32) -> f64 {
    if grid == 0 {
        return 0.0;
    }
    let exact = apply::eval_field(map, w, h, 0);
    let coarse = apply::eval_field(map, w, h, grid);
    exact
        .iter()
        .zip(&coarse)
        .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_error_vanishes_for_affine_maps_only() {
        let p = [[10.0, 10.0], [90.0, 15.0], [50.0, 70.0], [20.0, 95.0]];
        let aff: Vec<[f64; 2]> = p
            .iter()
            .map(|x| [1.1 * x[0] + 2.0, 0.9 * x[1] - x[0] * 0.1])
            .collect();
        let bent: Vec<[f64; 2]> = p
            .iter()
            .map(|x| [x[0] + 0.02 * x[1] * x[1], x[1]])
            .collect();
        let w = WarpParams {
            method: Method::MlsAffine,
            ..Default::default()
        };
        let f = fit(&w, &p, &aff).unwrap();
        assert!(grid_error(f.as_ref(), 100, 100, 16) < 1e-9);
        let g = fit(&w, &p, &bent).unwrap();
        assert!(grid_error(g.as_ref(), 100, 100, 16) > 1e-3);
        assert_eq!(grid_error(g.as_ref(), 100, 100, 0), 0.0);
    }

    #[test]
    fn check_points_refuses_each_degenerate_input() {
        let ok = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(check_points(Method::Rbf, &ok, &ok).is_ok());
        assert!(matches!(
            check_points(Method::Rbf, &ok, &ok[..2]),
            Err(WarpError::Mismatch { from: 3, to: 2 })
        ));
        assert!(matches!(
            check_points(Method::MlsAffine, &ok[..2], &ok[..2]),
            Err(WarpError::TooFew { need: 3, got: 2 })
        ));
        let dup = [[0.0, 0.0], [1.0, 0.0], [0.0, 0.0]];
        assert_eq!(
            check_points(Method::Idw, &dup, &ok),
            Err(WarpError::Coincident { i: 0, j: 2 })
        );
        let nan = [[0.0, 0.0], [1.0, f64::NAN], [0.0, 1.0]];
        let e = check_points(Method::Idw, &ok, &nan).unwrap_err();
        assert_eq!(e.side(), Side::To);
        let line = [[0.0, 0.0], [1.0, 1.0], [3.0, 3.0]];
        assert_eq!(
            check_points(Method::Rbf, &line, &ok),
            Err(WarpError::Collinear)
        );
        assert!(check_points(Method::MlsRigid, &line, &ok).is_ok());
    }
}
