//! Dirichlet (fixed-value) solves of a symmetric graph Laplacian (a mesh Laplacian with
//! uniform or cotangent weights): the block `L_II` of the free unknowns is assembled and
//! factored once (sparse Cholesky; in a nested-dissection order, on two cores when both halves
//! are large), then solved for given fixed values `x_B` and an optional right-hand side `b`:
//! `L_II x_I = b_I - L_IB x_B`. With `b = 0` this is the Laplace equation of Tutte's
//! embedding and of minimal surfaces; with `b` it is a Poisson problem `L x = b` with
//! Dirichlet boundary (e.g. Poisson image editing). All `D` coordinates share the factor.

use super::nested_dissection::Dissection;
use super::{SpdFactor, TwoDomainFactor};
use cgnodes_api::node::NodeError;
use faer::sparse::SparseColMat;
use faer::Mat;

/// A symmetric graph Laplacian as summed edge weights in compressed rows: row `i` of `L x` is
/// `sum_j w_ij (x_i - x_j)` over `j` in `col[start[i]..start[i + 1]]` (each neighbour once,
/// sorted), `w_ij` the matching entry of `weight`. Borrowed, so that the caller (e.g.
/// `param::laplacian_rows::LaplacianRows`) keeps its own storage.
#[derive(Clone, Copy, Debug)]
pub struct LaplaceRows<'a> {
    /// Row `i` is `col[start[i]..start[i + 1]]`.
    pub start: &'a [usize],
    /// Neighbour of each entry, sorted within a row.
    pub col: &'a [u32],
    /// Summed weight of each entry (`w_ij = w_ji`).
    pub weight: &'a [f64],
}

impl LaplaceRows<'_> {
    /// Number of vertices (rows).
    pub fn num_vertices(&self) -> usize {
        self.start.len() - 1
    }
}

/// The error of a Laplace system that could not be factored.
pub(crate) fn not_positive_definite(e: String) -> NodeError {
    NodeError::singular(format!(
        "the Laplace system is not positive definite ({e}); is every part of the mesh joined to the fixed boundary?"
    ))
}

/// Systems with at least this many free vertices solve their columns on two cores.
const SPLIT_SOLVE_ROWS: usize = 4096;

/// Systems whose two top-level nested-dissection halves each hold at least this many free
/// vertices are factored as two domains on two cores (`TwoDomainFactor`).
const TWO_DOMAIN_MIN_ROWS: usize = 4096;

/// Whether `order` holds each of `0..n` exactly once.
fn is_permutation(order: &[usize], n: usize) -> bool {
    let mut seen = vec![false; n];
    order.len() == n
        && order
            .iter()
            .all(|&v| v < n && !std::mem::replace(&mut seen[v], true))
}

/// Solves `sum_j w_ij (x_i - x_j) = 0` for every vertex where `fixed[i]` is `None`, the others
/// held at their values, with a sparse Cholesky factorization of the free-vertex block. `order`
/// (an elimination order of all vertices, e.g. `nested_dissection`) is
/// restricted to the free vertices; without it faer's AMD is used. A free vertex without
/// weights, or a system that is not positive definite, is an error.
pub fn solve_dirichlet<const D: usize>(
    rows: LaplaceRows<'_>,
    fixed: &[Option<[f64; D]>],
    order: Option<&Dissection>,
) -> Result<Vec<[f64; D]>, NodeError> {
    let is_fixed: Vec<bool> = fixed.iter().map(Option::is_some).collect();
    DirichletFactor::new(rows, &is_fixed, order)?.solve(rows, fixed)
}

/// Solves the Poisson problem `sum_j w_ij (x_i - x_j) = b_i` for every vertex where `fixed[i]`
/// is `None`, the others held at their values; otherwise like `solve_dirichlet` (which is this
/// with `b = 0`).
pub fn solve_poisson<const D: usize>(
    rows: LaplaceRows<'_>,
    fixed: &[Option<[f64; D]>],
    b: &[[f64; D]],
    order: Option<&Dissection>,
) -> Result<Vec<[f64; D]>, NodeError> {
    let is_fixed: Vec<bool> = fixed.iter().map(Option::is_some).collect();
    DirichletFactor::new(rows, &is_fixed, order)?.solve_poisson(rows, fixed, b)
}

/// The factored free-vertex block `L_II` of a Laplacian in rows, for a given set of fixed
/// vertices: built before the fixed values are known (they only enter the right-hand side).
pub struct DirichletFactor {
    /// Row of each vertex in the system, `u32::MAX` for fixed ones.
    index: Vec<u32>,
    /// The free vertices in row order.
    free: Vec<u32>,
    factor: Option<Factor>,
}

/// The factored free block: one factor, or two domains and their separator (one per
/// `DirichletFactor`, so the size difference between the variants does not matter).
#[allow(clippy::large_enum_variant)]
enum Factor {
    One(SpdFactor),
    Two(TwoDomainFactor),
}

/// Numbers the free vertices in elimination order when there is one (so the matrix is
/// assembled already permuted), by vertex otherwise: the row of each vertex (`u32::MAX` when
/// fixed), the free vertices by row, and how many free vertices fall in each of the order's
/// two top-level halves.
fn number_free(
    is_fixed: &[bool],
    order: Option<&[usize]>,
    halves: Option<[usize; 2]>,
) -> (Vec<u32>, Vec<u32>, [usize; 2]) {
    let n = is_fixed.len();
    let mut index = vec![u32::MAX; n];
    let mut free = Vec::new();
    let by_vertex = 0..n;
    let sequence: &mut dyn Iterator<Item = usize> = match order {
        Some(o) => &mut o.iter().copied(),
        None => &mut by_vertex.into_iter(),
    };
    // free vertices in each top-level half of the order
    let mut free_halves = [0usize; 2];
    for (k, v) in sequence.enumerate() {
        if !is_fixed[v] {
            index[v] = free.len() as u32;
            free.push(v as u32);
            if let Some([h0, h1]) = halves {
                if k < h0 + h1 {
                    free_halves[usize::from(k >= h0)] += 1;
                }
            }
        }
    }
    (index, free, free_halves)
}

/// `L_II` over the free vertices as one triangle by columns. By vertex (`upper` false): the
/// lower one, column c (free vertex v) holding the diagonal, then the free neighbours with a
/// larger row index, already sorted because rows are sorted by vertex. In elimination order
/// (`upper`): the upper one, column c holding the neighbours eliminated earlier (sorted
/// here), then the diagonal. `Err` for a free vertex without usable edge weights.
fn assemble_free_block(
    rows: LaplaceRows<'_>,
    index: &[u32],
    free: &[u32],
    upper: bool,
) -> Result<SparseColMat<usize, f64>, NodeError> {
    let nfree = free.len();
    let mut col_ptr = Vec::with_capacity(nfree + 1);
    let mut row_idx = Vec::with_capacity(rows.col.len() / 2 + nfree);
    let mut values = Vec::with_capacity(rows.col.len() / 2 + nfree);
    col_ptr.push(0usize);
    for (c, &v) in free.iter().enumerate() {
        let r = rows.start[v as usize]..rows.start[v as usize + 1];
        let first = values.len();
        if !upper {
            row_idx.push(c);
            values.push(0.0);
        }
        let mut diag = 0.0;
        for (&j, &w) in rows.col[r.clone()].iter().zip(&rows.weight[r]) {
            diag += w;
            let rj = index[j as usize];
            if rj != u32::MAX && ((rj as usize) < c) == upper && rj as usize != c {
                row_idx.push(rj as usize);
                values.push(-w);
            }
        }
        if diag.abs() <= 1e-300 || !diag.is_finite() {
            return Err(NodeError::singular(format!(
                "free vertex {v} has no usable edge weights (isolated or degenerate neighbourhood)"
            )));
        }
        if upper {
            // insertion sort of the few entries, values kept aligned; diagonal last
            for a in first + 1..row_idx.len() {
                let mut b = a;
                while b > first && row_idx[b - 1] > row_idx[b] {
                    row_idx.swap(b - 1, b);
                    values.swap(b - 1, b);
                    b -= 1;
                }
            }
            row_idx.push(c);
            values.push(diag);
        } else {
            values[first] = diag;
        }
        col_ptr.push(row_idx.len());
    }
    let symbolic =
        faer::sparse::SymbolicSparseColMat::new_checked(nfree, nfree, col_ptr, None, row_idx);
    Ok(SparseColMat::new(symbolic, values))
}

impl DirichletFactor {
    /// Assembles and factors `L_II` for the vertices where `is_fixed` is false, in `order`
    /// when given (faer's AMD otherwise); when both of the order's top-level halves keep at
    /// least `TWO_DOMAIN_MIN_ROWS` free vertices, the halves are factored on two cores.
    pub fn new(
        rows: LaplaceRows<'_>,
        is_fixed: &[bool],
        order: Option<&Dissection>,
    ) -> Result<DirichletFactor, NodeError> {
        let n = rows.num_vertices();
        if is_fixed.len() != n {
            return Err(NodeError::invalid(
                "mesh",
                format!(
                    "{} fixed flags for {n} vertices (internal size mismatch)",
                    is_fixed.len()
                ),
            ));
        }
        let halves = order.and_then(|d| d.halves);
        let order = order
            .map(|d| d.order.as_slice())
            .filter(|o| is_permutation(o, n));
        let (index, free, free_halves) = number_free(is_fixed, order, halves);
        let nfree = free.len();
        if nfree == 0 {
            return Ok(DirichletFactor {
                index,
                free,
                factor: None,
            });
        }
        let matrix = assemble_free_block(rows, &index, &free, order.is_some())?;
        let [f0, f1] = free_halves;
        let factor = match order {
            Some(_) if f0.min(f1) >= TWO_DOMAIN_MIN_ROWS && f0 + f1 < nfree => {
                TwoDomainFactor::from_upper_in_order(matrix.as_ref(), f0, f1).map(Factor::Two)
            }
            Some(_) => SpdFactor::from_upper_in_order(matrix, faer::Par::Seq).map(Factor::One),
            None => SpdFactor::from_lower(matrix, None, faer::Par::Seq).map(Factor::One),
        }
        .map_err(not_positive_definite)?;
        Ok(DirichletFactor {
            index,
            free,
            factor: Some(factor),
        })
    }

    /// Stored entries of the Cholesky factor (0 when every vertex is fixed): the fill-in the
    /// elimination order left.
    pub fn factor_nnz(&self) -> usize {
        match &self.factor {
            None => 0,
            Some(Factor::One(f)) => f.factor_nnz(),
            Some(Factor::Two(f)) => f.factor_nnz(),
        }
    }

    /// Whether this factor was built for exactly these fixed vertices.
    pub fn fixes(&self, is_fixed: &[bool]) -> bool {
        self.index.len() == is_fixed.len()
            && self
                .index
                .iter()
                .zip(is_fixed)
                .all(|(&r, &f)| (r == u32::MAX) == f)
    }

    /// The solution with the fixed vertices held at `fixed` (which must fix the same vertices
    /// the factor was built for; see `fixes`): the fixed values enter `-L_IB x_B`.
    pub fn solve<const D: usize>(
        &self,
        rows: LaplaceRows<'_>,
        fixed: &[Option<[f64; D]>],
    ) -> Result<Vec<[f64; D]>, NodeError> {
        self.solve_with(rows, fixed, None)
    }

    /// The solution of the Poisson problem `L x = b` on the free vertices (row `i`:
    /// `sum_j w_ij (x_i - x_j) = b_i`), the fixed vertices held at `fixed` as in `solve`.
    /// `b` has one entry per vertex; the entries of fixed vertices are not used.
    pub fn solve_poisson<const D: usize>(
        &self,
        rows: LaplaceRows<'_>,
        fixed: &[Option<[f64; D]>],
        b: &[[f64; D]],
    ) -> Result<Vec<[f64; D]>, NodeError> {
        if b.len() != fixed.len() {
            return Err(NodeError::invalid(
                "rhs",
                format!(
                    "{} right-hand side values for {} vertices",
                    b.len(),
                    fixed.len()
                ),
            ));
        }
        self.solve_with(rows, fixed, Some(b))
    }

    /// `solve` (no `b`) or `solve_poisson`.
    fn solve_with<const D: usize>(
        &self,
        rows: LaplaceRows<'_>,
        fixed: &[Option<[f64; D]>],
        b: Option<&[[f64; D]]>,
    ) -> Result<Vec<[f64; D]>, NodeError> {
        let mut out: Vec<[f64; D]> = fixed.iter().map(|f| f.unwrap_or([0.0; D])).collect();
        let Some(factor) = &self.factor else {
            return Ok(out);
        };
        let is_fixed: Vec<bool> = fixed.iter().map(Option::is_some).collect();
        if !self.fixes(&is_fixed) {
            return Err(NodeError::invalid(
                "mesh",
                "the fixed vertices differ from those the system was factored for (internal error)",
            ));
        }
        let mut rhs = Mat::<f64>::zeros(self.free.len(), D);
        for (c, &v) in self.free.iter().enumerate() {
            if let Some(b) = b {
                for (d, bd) in b[v as usize].iter().enumerate() {
                    rhs[(c, d)] = *bd;
                }
            }
            let r = rows.start[v as usize]..rows.start[v as usize + 1];
            for (&j, &w) in rows.col[r.clone()].iter().zip(&rows.weight[r]) {
                if let Some(x) = fixed[j as usize] {
                    for (d, xd) in x.iter().enumerate() {
                        rhs[(c, d)] += w * xd;
                    }
                }
            }
        }
        match factor {
            // the two domains already solve on two cores
            Factor::Two(f) => f.solve_in_place(rhs.as_mut()),
            Factor::One(f) if D > 1 && self.free.len() >= SPLIT_SOLVE_ROWS => {
                // first column on one core, the rest on another: the triangular solves are
                // memory-bound and both read the same factor
                let (a, b) = rhs.as_mut().split_at_col_mut(1);
                rayon::join(|| f.solve_in_place(a), || f.solve_in_place(b));
            }
            Factor::One(f) => f.solve_in_place(rhs.as_mut()),
        }
        for (c, &v) in self.free.iter().enumerate() {
            for d in 0..D {
                let val = rhs[(c, d)];
                if !val.is_finite() {
                    return Err(NodeError::singular(
                        "the Laplace solve produced non-finite values (singular system)",
                    ));
                }
                out[v as usize][d] = val;
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::super::nested_dissection::nested_dissection;
    use super::*;

    /// Rows of the 5-point Laplacian (unit weights) on a `(k + 1) x (k + 1)` grid, vertex
    /// `(i, j)` numbered `j (k + 1) + i`, with the grid points and the boundary flags.
    #[allow(clippy::type_complexity)]
    fn grid_rows(k: usize) -> (Vec<usize>, Vec<u32>, Vec<f64>, Vec<[f64; 3]>, Vec<bool>) {
        let id = |i: usize, j: usize| (j * (k + 1) + i) as u32;
        let (mut start, mut col, mut p, mut boundary) =
            (vec![0], Vec::new(), Vec::new(), Vec::new());
        for j in 0..=k {
            for i in 0..=k {
                // neighbours in increasing index order
                if j > 0 {
                    col.push(id(i, j - 1));
                }
                if i > 0 {
                    col.push(id(i - 1, j));
                }
                if i < k {
                    col.push(id(i + 1, j));
                }
                if j < k {
                    col.push(id(i, j + 1));
                }
                start.push(col.len());
                p.push([i as f64, j as f64, 0.0]);
                boundary.push(i == 0 || j == 0 || i == k || j == k);
            }
        }
        let weight = vec![1.0; col.len()];
        (start, col, weight, p, boundary)
    }

    /// A 120 x 120 grid is large enough for the two-domain factorization; the solve
    /// reproduces a linear (harmonic) function exactly, like the one-factor solve in AMD order.
    #[test]
    fn two_domain_solve_reproduces_a_linear_function() {
        let (start, col, weight, p, boundary) = grid_rows(120);
        let rows = LaplaceRows {
            start: &start,
            col: &col,
            weight: &weight,
        };
        let exact = |v: usize| [p[v][0] + 2.0 * p[v][1], 3.0 - 0.5 * p[v][0]];
        let fixed: Vec<Option<[f64; 2]>> = (0..p.len())
            .map(|v| boundary[v].then(|| exact(v)))
            .collect();
        let is_fixed: Vec<bool> = fixed.iter().map(Option::is_some).collect();
        let order = nested_dissection(&start, &col, &p, 64);
        let split = DirichletFactor::new(rows, &is_fixed, Some(&order)).unwrap();
        assert!(matches!(split.factor, Some(Factor::Two(_))));
        let amd = DirichletFactor::new(rows, &is_fixed, None).unwrap();
        assert!(matches!(amd.factor, Some(Factor::One(_))));
        for f in [&split, &amd] {
            let x = f.solve(rows, &fixed).unwrap();
            for (v, xv) in x.iter().enumerate() {
                let e = exact(v);
                assert!(
                    (xv[0] - e[0]).abs() < 1e-9 && (xv[1] - e[1]).abs() < 1e-9,
                    "{v}: {xv:?} vs {e:?}"
                );
            }
        }
    }

    /// `-x_{i-1} + 2 x_i - x_{i+1} = 1` on a path with both ends at 0: `x_i = i (n - i) / 2`.
    #[test]
    fn poisson_on_a_path_is_a_parabola() {
        let n = 6;
        let (mut start, mut col) = (vec![0], Vec::new());
        for i in 0..=n {
            if i > 0 {
                col.push(i as u32 - 1);
            }
            if i < n {
                col.push(i as u32 + 1);
            }
            start.push(col.len());
        }
        let weight = vec![1.0; col.len()];
        let rows = LaplaceRows {
            start: &start,
            col: &col,
            weight: &weight,
        };
        let fixed: Vec<Option<[f64; 1]>> = (0..=n)
            .map(|i| (i == 0 || i == n).then_some([0.0]))
            .collect();
        let b = vec![[1.0]; n + 1];
        let x = solve_poisson(rows, &fixed, &b, None).unwrap();
        for (i, xi) in x.iter().enumerate() {
            let want = (i * (n - i)) as f64 / 2.0;
            assert!((xi[0] - want).abs() < 1e-12, "{i}: {xi:?}");
        }
        // b = 0 is the Laplace solve: linear between the fixed values
        let fixed: Vec<Option<[f64; 1]>> = (0..=n)
            .map(|i| (i == 0 || i == n).then_some([i as f64]))
            .collect();
        let x = solve_dirichlet(rows, &fixed, None).unwrap();
        assert!(x
            .iter()
            .enumerate()
            .all(|(i, xi)| (xi[0] - i as f64).abs() < 1e-12));
        assert!(solve_poisson(rows, &fixed, &b[1..], None).is_err());
    }
}
