//! Discrete Laplacians on triangle meshes: uniform, cotangent and mean-value edge weights
//! (parameterization-specific; `tutte`, `minimal_surface` and `arap` use them).
//!
//! A Laplacian here is a list of directed edge weights `w_ij`: row `i` of the system is
//! `sum_j w_ij (x_i - x_j) = 0`. Symmetric weights (uniform, cotangent) give a symmetric
//! positive definite system once the fixed vertices move to the right-hand side; mean-value
//! weights are not symmetric. The Dirichlet solves live in `linalg::laplace` (symmetric
//! weights in rows, see `laplacian_rows`) and `linalg::laplace_weights` (any directed weights).

use faer::sparse::{SparseColMat, Triplet};
use rayon::prelude::*;

pub use cgnodes_linalg::laplace_weights::EdgeWeight;

/// Why Laplacian weights or the matrix cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LaplacianError {
    /// A zero-area triangle, where the angle-based weights are undefined.
    #[error("triangle {triangle} (vertices {vertices:?}) is degenerate (zero area); {weights} weights are undefined")]
    Degenerate {
        /// The triangle's index.
        triangle: usize,
        /// Its vertices.
        vertices: [u32; 3],
        /// Which weights: "cotangent" or "mean-value".
        weights: &'static str,
    },
    /// Mean-value weights asked for where the system must be symmetric.
    #[error("mean-value weights are not symmetric")]
    NotSymmetric,
    /// The sparse matrix could not be assembled (faer's error, debug-printed).
    #[error("{0}")]
    Assembly(String),
}

/// The cotangent of each corner's angle, per triangle: `cot[t][k]` is the cotangent of the
/// angle at corner `k` of triangle `t`, opposite the edge from corner `k+1` to corner `k+2`.
/// A degenerate (zero-area) triangle gives an error naming it.
pub fn corner_cotangents(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<Vec<[f64; 3]>, LaplacianError> {
    triangles
        .par_iter()
        .enumerate()
        .map(|(t, tri)| {
            let p = tri.map(|v| positions[v as usize]);
            let mut c = [0.0; 3];
            for k in 0..3 {
                let a = sub(p[(k + 1) % 3], p[k]);
                let b = sub(p[(k + 2) % 3], p[k]);
                let cr = norm(cross(a, b));
                // cot = cos / sin = (a.b) / |a x b|
                if cr <= 1e-300 || !cr.is_finite() {
                    return Err(LaplacianError::Degenerate {
                        triangle: t,
                        vertices: *tri,
                        weights: "cotangent",
                    });
                }
                c[k] = dot(a, b) / cr;
            }
            Ok(c)
        })
        .collect()
}

/// Cotangent weights `w_ij = (cot a_ij + cot b_ij) / 2` (Pinkall and Polthier 1993, eq. 5;
/// Meyer et al. 2003): each triangle adds half the cotangent of a corner to the opposite edge,
/// in both directions. Returns the directed weights (duplicates to be summed) and how many
/// undirected edges end up with a negative weight (obtuse opposite angles).
pub fn cotangent_weights(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<(Vec<EdgeWeight>, usize), LaplacianError> {
    let cot = corner_cotangents(positions, triangles)?;
    let w: Vec<EdgeWeight> = triangles
        .par_iter()
        .zip(&cot)
        .flat_map_iter(|(tri, c)| {
            (0..3).flat_map(move |k| {
                let (i, j) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                [(i, j, 0.5 * c[k]), (j, i, 0.5 * c[k])]
            })
        })
        .collect();
    let negative = count_negative_edges(&w);
    Ok((w, negative))
}

/// Floater's mean-value weights (Floater 2003, eq. 5.1):
/// `w_ij = (tan(a_ij / 2) + tan(b_ij / 2)) / |x_i - x_j|`, with `a_ij`, `b_ij` the angles at
/// `x_i` of the two triangles beside edge `ij`. Always positive, not symmetric; they reproduce
/// planar meshes exactly (linear precision). `tan(t/2) = (|a||b| - a.b) / |a x b|`.
pub fn mean_value_weights(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<Vec<EdgeWeight>, LaplacianError> {
    let mut w = Vec::with_capacity(triangles.len() * 6);
    for (t, tri) in triangles.iter().enumerate() {
        let p = tri.map(|v| positions[v as usize]);
        for k in 0..3 {
            let a = sub(p[(k + 1) % 3], p[k]);
            let b = sub(p[(k + 2) % 3], p[k]);
            let (la, lb) = (norm(a), norm(b));
            let cr = norm(cross(a, b));
            if cr <= 1e-300 || la <= 0.0 || lb <= 0.0 {
                return Err(LaplacianError::Degenerate {
                    triangle: t,
                    vertices: *tri,
                    weights: "mean-value",
                });
            }
            let half_tan = (la * lb - dot(a, b)) / cr;
            w.push((tri[k], tri[(k + 1) % 3], half_tan / la));
            w.push((tri[k], tri[(k + 2) % 3], half_tan / lb));
        }
    }
    Ok(w)
}

/// The cotangent Laplacian `L` (n x n, symmetric positive semidefinite, both triangles stored):
/// `L_ij = -w_ij`, `L_ii = sum_j w_ij`, so `x^T L x` is twice the Dirichlet energy of the
/// piecewise-linear function `x`.
pub fn cotangent_laplacian(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<SparseColMat<usize, f64>, LaplacianError> {
    let (w, _) = cotangent_weights(positions, triangles)?;
    laplacian_matrix(positions.len(), &w)
}

/// The Laplacian matrix of directed weights: `L_ij = -w_ij`, `L_ii = sum_j w_ij`.
pub fn laplacian_matrix(
    n: usize,
    weights: &[EdgeWeight],
) -> Result<SparseColMat<usize, f64>, LaplacianError> {
    let mut trip = Vec::with_capacity(weights.len() + n);
    let mut diag = vec![0.0; n];
    for &(i, j, w) in weights {
        trip.push(Triplet::new(i as usize, j as usize, -w));
        diag[i as usize] += w;
    }
    trip.extend(diag.iter().enumerate().map(|(i, &d)| Triplet::new(i, i, d)));
    SparseColMat::try_new_from_triplets(n, n, &trip)
        .map_err(|e| LaplacianError::Assembly(format!("{e:?}")))
}

/// Number of undirected edges whose summed weight is negative.
pub fn count_negative_edges(weights: &[EdgeWeight]) -> usize {
    let mut keyed: Vec<(u64, f64)> = weights
        .iter()
        .filter(|(i, j, _)| i < j)
        .map(|&(i, j, w)| (((i as u64) << 32) | j as u64, w))
        .collect();
    keyed.par_sort_unstable_by_key(|k| k.0);
    let mut count = 0;
    let mut k = 0;
    while k < keyed.len() {
        let mut s = 0.0;
        let key = keyed[k].0;
        while k < keyed.len() && keyed[k].0 == key {
            s += keyed[k].1;
            k += 1;
        }
        if s < 0.0 {
            count += 1;
        }
    }
    count
}

use cgnodes_api::types::vec3::{cross, dot, norm, sub};

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;

    #[test]
    fn equilateral_cotangents_and_laplacian_kills_linear_functions() {
        let s = 3f64.sqrt() / 2.0;
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, s, 0.0],
            [0.5, -s, 0.0],
        ];
        let t = [[0, 1, 2], [0, 3, 1]];
        let c = corner_cotangents(&p, &t).unwrap();
        for ck in c[0] {
            assert!((ck - 1.0 / 3f64.sqrt()).abs() < 1e-12);
        }
        // L applied to a linear function vanishes at the interior edge's rows up to boundary terms;
        // on a whole closed-up planar fan the row sums are zero.
        let l = cotangent_laplacian(&p, &t).unwrap();
        let ones = Mat::<f64>::from_fn(4, 1, |_, _| 1.0);
        let r = &l * &ones;
        assert!(r.norm_l2() < 1e-12);
        // symmetric
        let dense = l.to_dense();
        for i in 0..4 {
            for j in 0..4 {
                assert!((dense[(i, j)] - dense[(j, i)]).abs() < 1e-14);
            }
        }
        // the shared edge 0-1 gets (cot 60 + cot 60)/2
        assert!((dense[(0, 1)] + 1.0 / 3f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn degenerate_triangle_is_an_error() {
        let p = vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        assert!(corner_cotangents(&p, &[[0, 1, 2]])
            .unwrap_err()
            .to_string()
            .contains("degenerate"));
    }
}
