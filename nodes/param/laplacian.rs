//! Discrete Laplacians on triangle meshes and the Dirichlet (fixed-boundary) Laplace solve
//! shared by `tutte`, `minimal_surface` and `arap`.
//!
//! A Laplacian here is a list of directed edge weights `w_ij`: row `i` of the system is
//! `sum_j w_ij (x_i - x_j) = 0`. Symmetric weights (uniform, cotangent) give a symmetric
//! positive definite system once the fixed vertices move to the right-hand side and are solved
//! with a sparse Cholesky factorization; mean-value weights are not symmetric and use a
//! sparse LU factorization. All coordinates are solved with one factorization (multi-column
//! right-hand side).

use super::nested_dissection::nested_dissection_order;
use crate::nodes::linalg::spd::SpdFactor;
use crate::prelude::*;
use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;
use rayon::prelude::*;

/// A directed edge weight: row vertex, column vertex, weight.
pub type EdgeWeight = (u32, u32, f64);

/// The cotangent of each corner's angle, per triangle: `cot[t][k]` is the cotangent of the
/// angle at corner `k` of triangle `t`, opposite the edge from corner `k+1` to corner `k+2`.
/// A degenerate (zero-area) triangle gives an error naming it.
pub fn corner_cotangents(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<Vec<[f64; 3]>, String> {
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
                    return Err(format!(
                        "triangle {t} (vertices {:?}) is degenerate (zero area); cotangent weights are undefined",
                        tri
                    ));
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
) -> Result<(Vec<EdgeWeight>, usize), String> {
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
) -> Result<Vec<EdgeWeight>, String> {
    let mut w = Vec::with_capacity(triangles.len() * 6);
    for (t, tri) in triangles.iter().enumerate() {
        let p = tri.map(|v| positions[v as usize]);
        for k in 0..3 {
            let a = sub(p[(k + 1) % 3], p[k]);
            let b = sub(p[(k + 2) % 3], p[k]);
            let (la, lb) = (norm(a), norm(b));
            let cr = norm(cross(a, b));
            if cr <= 1e-300 || la <= 0.0 || lb <= 0.0 {
                return Err(format!(
                    "triangle {t} (vertices {:?}) is degenerate (zero area); mean-value weights are undefined",
                    tri
                ));
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
) -> Result<SparseColMat<usize, f64>, String> {
    let (w, _) = cotangent_weights(positions, triangles)?;
    laplacian_matrix(positions.len(), &w)
}

/// The Laplacian matrix of directed weights: `L_ij = -w_ij`, `L_ii = sum_j w_ij`.
pub fn laplacian_matrix(
    n: usize,
    weights: &[EdgeWeight],
) -> Result<SparseColMat<usize, f64>, String> {
    let mut trip = Vec::with_capacity(weights.len() + n);
    let mut diag = vec![0.0; n];
    for &(i, j, w) in weights {
        trip.push(Triplet::new(i as usize, j as usize, -w));
        diag[i as usize] += w;
    }
    trip.extend(diag.iter().enumerate().map(|(i, &d)| Triplet::new(i, i, d)));
    SparseColMat::try_new_from_triplets(n, n, &trip).map_err(|e| format!("{e:?}"))
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
/// The interior (free-vertex) block of a Laplace system with Dirichlet conditions, ready to
/// factor: `matrix` (only the lower triangle when assembled as symmetric), the right-hand side
/// with one column per coordinate, and the row of each vertex (`u32::MAX` for fixed ones).
pub struct DirichletSystem<const D: usize> {
    /// Free-vertex system matrix, `L_II`.
    pub matrix: SparseColMat<usize, f64>,
    /// `-L_IB x_B`, one column per coordinate.
    pub rhs: Mat<f64>,
    /// Row of each vertex in the system, `u32::MAX` for fixed vertices.
    pub index: Vec<u32>,
}

/// Assembles the free-vertex system of `sum_j w_ij (x_i - x_j) = 0` with the vertices where
/// `fixed[i]` is `Some` moved to the right-hand side. With `symmetric`, only the lower triangle
/// is stored (for a Cholesky factorization). Duplicate weights are summed. Entries are bucketed
/// by column with a counting sort (linear time), then each short column is sorted.
pub fn assemble_dirichlet<const D: usize>(
    weights: &[EdgeWeight],
    fixed: &[Option<[f64; D]>],
    symmetric: bool,
) -> Result<DirichletSystem<D>, NodeError> {
    let n = fixed.len();
    let mut index = vec![u32::MAX; n];
    let mut nfree = 0usize;
    for (v, f) in fixed.iter().enumerate() {
        if f.is_none() {
            index[v] = nfree as u32;
            nfree += 1;
        }
    }
    let mut diag = vec![0.0; nfree];
    let mut rhs = Mat::<f64>::zeros(nfree, D);
    // count off-diagonal entries per column
    let mut col_start = vec![0usize; nfree + 2];
    for &(i, j, _) in weights {
        let (ri, cj) = (index[i as usize], index[j as usize]);
        if ri != u32::MAX && cj != u32::MAX && (!symmetric || ri > cj) {
            col_start[cj as usize + 2] += 1;
        }
    }
    // one diagonal entry per column
    for c in 0..nfree {
        col_start[c + 2] += 1;
    }
    for c in 1..nfree + 2 {
        col_start[c] += col_start[c - 1];
    }
    let nnz = col_start[nfree + 1];
    let mut rows = vec![0u32; nnz];
    let mut vals = vec![0.0f64; nnz];
    // fill: col_start[c + 1] is the next free slot of column c
    for &(i, j, w) in weights {
        let ri = index[i as usize];
        if ri == u32::MAX {
            continue;
        }
        diag[ri as usize] += w;
        let cj = index[j as usize];
        if cj == u32::MAX {
            let x = fixed[j as usize].unwrap_or([0.0; D]);
            for (d, xd) in x.iter().enumerate() {
                rhs[(ri as usize, d)] += w * xd;
            }
        } else if !symmetric || ri > cj {
            let s = &mut col_start[cj as usize + 1];
            rows[*s] = ri;
            vals[*s] = -w;
            *s += 1;
        }
    }
    for (c, &d) in diag.iter().enumerate() {
        if d.abs() <= 1e-300 || !d.is_finite() {
            let v = index.iter().position(|&r| r == c as u32).unwrap_or(0);
            return Err(NodeError::singular(format!(
                "free vertex {v} has no usable edge weights (isolated or degenerate neighbourhood)"
            )));
        }
        let s = &mut col_start[c + 1];
        rows[*s] = c as u32;
        vals[*s] = d;
        *s += 1;
    }
    // col_start[c] .. col_start[c + 1] is now column c; sort rows and merge duplicates
    let mut col_ptr = Vec::with_capacity(nfree + 1);
    let mut row_idx = Vec::with_capacity(nnz);
    let mut values = Vec::with_capacity(nnz);
    let mut pairs: Vec<(u32, f64)> = Vec::new();
    col_ptr.push(0usize);
    for c in 0..nfree {
        pairs.clear();
        pairs.extend((col_start[c]..col_start[c + 1]).map(|k| (rows[k], vals[k])));
        pairs.sort_unstable_by_key(|p| p.0);
        for &(r, v) in &pairs {
            if row_idx.len() > col_ptr[c] && row_idx.last() == Some(&(r as usize)) {
                *values.last_mut().unwrap() += v;
            } else {
                row_idx.push(r as usize);
                values.push(v);
            }
        }
        col_ptr.push(row_idx.len());
    }
    let symbolic =
        faer::sparse::SymbolicSparseColMat::new_checked(nfree, nfree, col_ptr, None, row_idx);
    let matrix = SparseColMat::new(symbolic, values);
    Ok(DirichletSystem { matrix, rhs, index })
}

/// Solves `A X = B` for a symmetric positive definite `A` given by its lower triangle, with a
/// sparse Cholesky factorization (faer picks simplicial or supernodal). With `coords` (one
/// point per row, e.g. the vertex positions) and more than a few thousand rows, the
/// fill-reducing order is geometric nested dissection (`nested_dissection.rs`), several times
/// cheaper than AMD on meshes; otherwise AMD.
pub fn solve_spd_lower(
    a: &SparseColMat<usize, f64>,
    b: &Mat<f64>,
    coords: Option<&[[f64; 3]]>,
) -> Result<Mat<f64>, NodeError> {
    let n = a.nrows();
    let nd = coords.filter(|c| c.len() == n && n > ND_MIN_ROWS).map(|c| {
        let (start, adj) = symmetric_adjacency(a);
        nested_dissection_order(&start, &adj, c, 64)
    });
    solve_spd_lower_ordered(a, b, nd.as_deref())
}

/// `solve_spd_lower` with a given elimination order (the `k`-th entry is the row eliminated
/// `k`-th), or faer's AMD without one. The factorization and solves run on one thread: on the
/// 2-core machines we measure, faer's parallel supernodal factorization of mesh Laplacians
/// (22k to 77k rows) took 1.5 to 2.5 times as long as the sequential one.
pub fn solve_spd_lower_ordered(
    a: &SparseColMat<usize, f64>,
    b: &Mat<f64>,
    order: Option<&[usize]>,
) -> Result<Mat<f64>, NodeError> {
    let factor =
        SpdFactor::from_lower(a.clone(), order, faer::Par::Seq).map_err(not_positive_definite)?;
    let mut x = b.clone();
    factor.solve_in_place(x.as_mut());
    Ok(x)
}

/// The error of a Laplace system that could not be factored.
pub(crate) fn not_positive_definite(e: String) -> NodeError {
    NodeError::singular(format!(
        "the Laplace system is not positive definite ({e}); is every part of the mesh joined to the fixed boundary?"
    ))
}

/// Below this many rows AMD is cheap enough and nested dissection is not used.
pub const ND_MIN_ROWS: usize = 4000;

/// Both-ways adjacency (compressed rows) of a matrix stored as its lower triangle, diagonal left out.
fn symmetric_adjacency(a: &SparseColMat<usize, f64>) -> (Vec<usize>, Vec<u32>) {
    let n = a.nrows();
    let cp = a.symbolic().col_ptr();
    let ri = a.symbolic().row_idx();
    let mut start = vec![0usize; n + 1];
    for c in 0..n {
        for &r in &ri[cp[c]..cp[c + 1]] {
            if r != c {
                start[r + 1] += 1;
                start[c + 1] += 1;
            }
        }
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut adj = vec![0u32; start[n]];
    for c in 0..n {
        for &r in &ri[cp[c]..cp[c + 1]] {
            if r != c {
                adj[fill[r]] = c as u32;
                fill[r] += 1;
                adj[fill[c]] = r as u32;
                fill[c] += 1;
            }
        }
    }
    (start, adj)
}

/// Solves the Laplace equation `sum_j w_ij (x_i - x_j) = 0` for every free vertex `i`, with
/// the vertices where `fixed[i]` is `Some` held at those values (Dirichlet conditions moved
/// to the right-hand side). `symmetric` selects a sparse Cholesky factorization (the weights
/// must then be symmetric, `w_ij = w_ji`); otherwise a sparse LU. All `D` coordinates share
/// one factorization. A free vertex without weights, or a singular system, is an error.
pub fn solve_dirichlet<const D: usize>(
    weights: &[EdgeWeight],
    fixed: &[Option<[f64; D]>],
    symmetric: bool,
) -> Result<Vec<[f64; D]>, NodeError> {
    solve_dirichlet_on(weights, fixed, symmetric, None)
}

/// `solve_dirichlet` with the vertex positions (one per entry of `fixed`), which let the
/// Cholesky factorization use a geometric nested-dissection ordering on large meshes.
pub fn solve_dirichlet_on<const D: usize>(
    weights: &[EdgeWeight],
    fixed: &[Option<[f64; D]>],
    symmetric: bool,
    positions: Option<&[[f64; 3]]>,
) -> Result<Vec<[f64; D]>, NodeError> {
    let mut out: Vec<[f64; D]> = fixed.iter().map(|f| f.unwrap_or([0.0; D])).collect();
    if fixed.iter().all(|f| f.is_some()) {
        return Ok(out);
    }
    let sys = assemble_dirichlet(weights, fixed, symmetric)?;
    let x = if symmetric {
        let coords: Option<Vec<[f64; 3]>> = positions.filter(|p| p.len() == fixed.len()).map(|p| {
            let mut c = vec![[0.0; 3]; sys.rhs.nrows()];
            for (v, &r) in sys.index.iter().enumerate() {
                if r != u32::MAX {
                    c[r as usize] = p[v];
                }
            }
            c
        });
        solve_spd_lower(&sys.matrix, &sys.rhs, coords.as_deref())?
    } else {
        sys.matrix
            .sp_lu()
            .map_err(|e| NodeError::singular(format!("the Laplace system is singular ({e:?})")))?
            .solve(&sys.rhs)
    };
    for (v, &r) in sys.index.iter().enumerate() {
        if r != u32::MAX {
            for d in 0..D {
                let val = x[(r as usize, d)];
                if !val.is_finite() {
                    return Err(NodeError::singular(
                        "the Laplace solve produced non-finite values (singular system)",
                    ));
                }
                out[v][d] = val;
            }
        }
    }
    Ok(out)
}

/// Splits every polygon into a fan of triangles from its first corner.
pub fn fan_triangles(mesh: &Mesh) -> Vec<[u32; 3]> {
    if let Some(t) = mesh.triangles() {
        return t;
    }
    let mut out = Vec::new();
    for f in mesh.faces() {
        for k in 1..f.len() - 1 {
            out.push([f[0], f[k], f[k + 1]]);
        }
    }
    out
}

pub(crate) use crate::types::vec3::{cross, dot, norm, sub};

#[cfg(test)]
mod tests {
    use super::*;

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
            .contains("degenerate"));
    }

    #[test]
    fn dirichlet_on_a_path_is_linear() {
        // path 0-1-2-3 with ends fixed at 0 and 3: interior values 1 and 2
        let w: Vec<EdgeWeight> = (0..3u32)
            .flat_map(|i| [(i, i + 1, 1.0), (i + 1, i, 1.0)])
            .collect();
        let fixed = vec![Some([0.0]), None, None, Some([3.0])];
        for sym in [true, false] {
            let x = solve_dirichlet(&w, &fixed, sym).unwrap();
            assert!((x[1][0] - 1.0).abs() < 1e-12 && (x[2][0] - 2.0).abs() < 1e-12);
        }
        // a free vertex without weights is refused, not a panic
        let fixed = vec![Some([0.0]), None, None, Some([3.0]), None];
        assert!(solve_dirichlet(&w, &fixed, true).is_err());
    }
}
