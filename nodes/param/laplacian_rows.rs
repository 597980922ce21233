//! A symmetric mesh Laplacian kept as summed edge weights in compressed rows, and the Dirichlet
//! (fixed-boundary) solve on it.
//!
//! Row `i` lists every neighbour `j` once, sorted, with the summed weight `w_ij` of all the
//! triangles beside edge `ij`. One pass over the triangles builds it, without the global sort
//! of a triplet list; the same rows then give the graph for the fill-reducing order, the count
//! of negative (cotangent) weights and the lower triangle of the free-vertex system, whose
//! columns come out sorted. `tutte` and `minimal_surface` build it while the mesh connectivity
//! is being built on the other core.

use super::laplacian::{corner_cotangents, not_positive_definite, ND_MIN_ROWS};
use super::nested_dissection::{nested_dissection, Dissection};
use crate::nodes::linalg::{SpdFactor, TwoDomainFactor};
use crate::prelude::*;
use faer::sparse::SparseColMat;
use faer::Mat;

/// Summed symmetric edge weights in compressed rows (see the module documentation).
#[derive(Clone, Debug)]
pub struct LaplacianRows {
    /// Row `i` is `col[start[i]..start[i + 1]]`.
    pub start: Vec<usize>,
    /// Neighbour of each entry, sorted within a row.
    pub col: Vec<u32>,
    /// Summed weight of each entry.
    pub weight: Vec<f64>,
    /// Vertices on an edge with a single triangle (the boundary of a manifold mesh).
    pub on_boundary: Vec<bool>,
}

impl LaplacianRows {
    /// Rows of `n` vertices from per-corner weights: `corner_weight[t][k]` is added to the
    /// edge opposite corner `k` of triangle `t`, in both directions (the cotangent formula
    /// `w_ij = (cot a_ij + cot b_ij) / 2` is `corner_weight = cot / 2`).
    pub fn from_corner_weights(
        n: usize,
        triangles: &[[u32; 3]],
        corner_weight: &[[f64; 3]],
    ) -> LaplacianRows {
        Self::build(n, triangles, |t, k| corner_weight[t][k])
    }

    /// Uniform weights, or with `cotangent` the cotangent weights of the triangles at
    /// `positions` (an error names a degenerate triangle).
    pub fn symmetric(
        positions: &[[f64; 3]],
        triangles: &[[u32; 3]],
        cotangent: bool,
    ) -> Result<LaplacianRows, String> {
        let n = positions.len();
        if !cotangent {
            return Ok(Self::uniform(n, triangles));
        }
        let half: Vec<[f64; 3]> = corner_cotangents(positions, triangles)?
            .iter()
            .map(|c| c.map(|x| 0.5 * x))
            .collect();
        Ok(Self::from_corner_weights(n, triangles, &half))
    }

    /// Uniform weights (Tutte 1963): 1/2 per triangle beside an edge, so 1 for interior edges.
    pub fn uniform(n: usize, triangles: &[[u32; 3]]) -> LaplacianRows {
        Self::build(n, triangles, |_, _| 0.5)
    }

    fn build(
        n: usize,
        triangles: &[[u32; 3]],
        corner_weight: impl Fn(usize, usize) -> f64,
    ) -> LaplacianRows {
        let mut count = vec![0usize; n + 1];
        for tri in triangles {
            for &v in tri {
                count[v as usize + 1] += 2;
            }
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut raw: Vec<(u32, f64)> = vec![(0, 0.0); count[n]];
        for (t, tri) in triangles.iter().enumerate() {
            for k in 0..3 {
                let (i, j) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                let w = corner_weight(t, k);
                raw[fill[i as usize]] = (j, w);
                fill[i as usize] += 1;
                raw[fill[j as usize]] = (i, w);
                fill[j as usize] += 1;
            }
        }
        // sort each short row and merge the duplicates (each interior edge appears twice)
        let mut start = Vec::with_capacity(n + 1);
        let mut col = Vec::with_capacity(count[n] / 2 + n);
        let mut weight = Vec::with_capacity(count[n] / 2 + n);
        let mut on_boundary = vec![false; n];
        start.push(0);
        for (i, boundary) in on_boundary.iter_mut().enumerate() {
            let row = &mut raw[count[i]..count[i + 1]];
            row.sort_unstable_by_key(|e| e.0);
            let mut k = 0;
            while k < row.len() {
                let j = row[k].0;
                let mut w = 0.0;
                let mut times = 0;
                while k < row.len() && row[k].0 == j {
                    w += row[k].1;
                    times += 1;
                    k += 1;
                }
                *boundary |= times == 1;
                col.push(j);
                weight.push(w);
            }
            start.push(col.len());
        }
        LaplacianRows {
            start,
            col,
            weight,
            on_boundary,
        }
    }

    /// Number of vertices (rows).
    pub fn num_vertices(&self) -> usize {
        self.start.len() - 1
    }

    /// Undirected edges whose summed weight is negative (obtuse opposite angles for cotangent
    /// weights).
    pub fn negative_edges(&self) -> usize {
        (0..self.num_vertices())
            .map(|i| {
                let r = self.start[i]..self.start[i + 1];
                self.col[r.clone()]
                    .iter()
                    .zip(&self.weight[r])
                    .filter(|&(&j, &w)| (j as usize) > i && w < 0.0)
                    .count()
            })
            .sum()
    }

    /// Elimination order of all vertices by geometric nested dissection (see
    /// `nested_dissection.rs`), for the factorization of any free-vertex block.
    pub fn nested_dissection(&self, positions: &[[f64; 3]]) -> Dissection {
        nested_dissection(&self.start, &self.col, positions, 64)
    }

    /// `nested_dissection` for meshes with more than `ND_MIN_ROWS` vertices; `None`
    /// (faer's AMD) for smaller ones, where AMD is cheap.
    pub fn fill_reducing_order(&self, positions: &[[f64; 3]]) -> Option<Dissection> {
        (self.num_vertices() > ND_MIN_ROWS).then(|| self.nested_dissection(positions))
    }

    /// Vertices held fixed when nothing else is known: those on the boundary (an edge with a
    /// single triangle) and those no triangle uses.
    pub fn boundary_or_unused(&self) -> Vec<bool> {
        (0..self.num_vertices())
            .map(|v| self.on_boundary[v] || self.start[v] == self.start[v + 1])
            .collect()
    }
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
/// (an elimination order of all vertices, e.g. `LaplacianRows::nested_dissection`) is
/// restricted to the free vertices; without it faer's AMD is used. A free vertex without
/// weights, or a system that is not positive definite, is an error.
pub fn solve_dirichlet_rows<const D: usize>(
    rows: &LaplacianRows,
    fixed: &[Option<[f64; D]>],
    order: Option<&Dissection>,
) -> Result<Vec<[f64; D]>, NodeError> {
    let is_fixed: Vec<bool> = fixed.iter().map(Option::is_some).collect();
    DirichletFactor::new(rows, &is_fixed, order)?.solve(rows, fixed)
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

impl DirichletFactor {
    /// Assembles and factors `L_II` for the vertices where `is_fixed` is false, in `order`
    /// when given (faer's AMD otherwise); when both of the order's top-level halves keep at
    /// least `TWO_DOMAIN_MIN_ROWS` free vertices, the halves are factored on two cores.
    pub fn new(
        rows: &LaplacianRows,
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
        // Free vertices numbered in elimination order when there is one (the matrix is then
        // assembled already permuted), by vertex otherwise.
        let halves = order.and_then(|d| d.halves);
        let order = order
            .map(|d| d.order.as_slice())
            .filter(|o| is_permutation(o, n));
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
        let nfree = free.len();
        if nfree == 0 {
            return Ok(DirichletFactor {
                index,
                free,
                factor: None,
            });
        }
        // One triangle by columns. By vertex: the lower one, column c (free vertex v) holding
        // the diagonal, then the free neighbours with a larger row index, already sorted
        // because rows are sorted by vertex. In elimination order: the upper one, column c
        // holding the neighbours eliminated earlier (sorted here), then the diagonal.
        let upper = order.is_some();
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
        let matrix = SparseColMat::new(symbolic, values);
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
        rows: &LaplacianRows,
        fixed: &[Option<[f64; D]>],
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
                // memory-bound and both read the same factor (nefertiti_front: 4.4 -> 3.6 ms)
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
    use super::super::laplacian::{cotangent_weights, fan_triangles, solve_dirichlet};
    use super::*;

    /// A 6 x 6 grid of squares split into triangles (vertex `(i, j)` is `7 j + i`), jittered
    /// and bent so the weights differ.
    fn grid() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let mesh =
            crate::nodes::sim::mass_spring::grid::grid_mesh(6, 6, [6.0, 6.0], "xy", [3.0; 3], true)
                .unwrap();
        let p = (0..49)
            .map(|v| {
                let (i, j) = (v % 7, v / 7);
                let jitter = ((i * 7 + j * 13) % 5) as f64 * 0.03;
                [i as f64 + jitter, j as f64 - jitter, 0.1 * (i * j) as f64]
            })
            .collect();
        (p, fan_triangles(&mesh))
    }

    #[test]
    fn rows_solve_matches_the_triplet_assembly() {
        let (p, t) = grid();
        let n = p.len();
        let (w, neg) = cotangent_weights(&p, &t).unwrap();
        let rows = LaplacianRows::symmetric(&p, &t, true).unwrap();
        assert_eq!(rows.negative_edges(), neg);
        // every interior edge merged: 6x6 grid with diagonals has 7*6*2 + 36 = 120 edges
        assert_eq!(rows.col.len(), 2 * 120);
        let fixed: Vec<Option<[f64; 2]>> = (0..n)
            .map(|v| {
                let (i, j) = (v % 7, v / 7);
                (i == 0 || j == 0 || i == 6 || j == 6).then_some([i as f64, (j * j) as f64])
            })
            .collect();
        let a = solve_dirichlet(&w, &fixed, true).unwrap();
        // nested dissection (one leaf here: input order), reversed, and scrambled orders
        // exercise the assembly in elimination order and its per-column sort
        let order = rows.nested_dissection(&p);
        let plain = |order| Dissection {
            order,
            halves: None,
        };
        let reversed = plain((0..n).rev().collect());
        let scrambled = plain((0..n).map(|k| (k * 17 + 5) % n).collect());
        for ord in [None, Some(&order), Some(&reversed), Some(&scrambled)] {
            let b = solve_dirichlet_rows(&rows, &fixed, ord).unwrap();
            for (x, y) in a.iter().zip(&b) {
                assert!((x[0] - y[0]).abs() < 1e-12 && (x[1] - y[1]).abs() < 1e-12);
            }
        }
    }

    /// A 120 x 120 grid (uniform weights reproduce linear functions) is large enough for the
    /// two-domain factorization; the solve is exact against the analytic solution, like the
    /// one-factor solve in AMD order.
    #[test]
    fn two_domain_solve_reproduces_a_linear_function() {
        let k = 120;
        let id = |i: usize, j: usize| (j * (k + 1) + i) as u32;
        let mut p = Vec::new();
        let mut t = Vec::new();
        for j in 0..=k {
            for i in 0..=k {
                p.push([i as f64, j as f64, 0.0]);
                if i < k && j < k {
                    t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                    t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
                }
            }
        }
        let rows = LaplacianRows::uniform(p.len(), &t);
        let exact = |v: usize| [p[v][0] + 2.0 * p[v][1], 3.0 - 0.5 * p[v][0]];
        let fixed: Vec<Option<[f64; 2]>> = (0..p.len())
            .map(|v| rows.on_boundary[v].then(|| exact(v)))
            .collect();
        let is_fixed: Vec<bool> = fixed.iter().map(Option::is_some).collect();
        let order = rows.nested_dissection(&p);
        let split = DirichletFactor::new(&rows, &is_fixed, Some(&order)).unwrap();
        assert!(matches!(split.factor, Some(Factor::Two(_))));
        let amd = DirichletFactor::new(&rows, &is_fixed, None).unwrap();
        assert!(matches!(amd.factor, Some(Factor::One(_))));
        for f in [&split, &amd] {
            let x = f.solve(&rows, &fixed).unwrap();
            for (v, xv) in x.iter().enumerate() {
                let e = exact(v);
                assert!(
                    (xv[0] - e[0]).abs() < 1e-9 && (xv[1] - e[1]).abs() < 1e-9,
                    "{v}: {xv:?} vs {e:?}"
                );
            }
        }
    }

    #[test]
    fn a_free_vertex_without_weights_is_an_error() {
        let (p, t) = grid();
        let rows = LaplacianRows::uniform(p.len() + 1, &t);
        let mut fixed: Vec<Option<[f64; 1]>> = vec![Some([0.0]); p.len() + 1];
        fixed[p.len()] = None; // a vertex no triangle uses, left free
        let e = solve_dirichlet_rows(&rows, &fixed, None).unwrap_err();
        assert!(
            e.message.contains("no usable edge weights"),
            "{}",
            e.message
        );
    }
}
