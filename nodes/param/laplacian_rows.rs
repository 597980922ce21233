//! A symmetric mesh Laplacian kept as summed edge weights in compressed rows (uniform or
//! cotangent weights), ready for the Dirichlet solve of `linalg::laplace`.
//!
//! Row `i` lists every neighbour `j` once, sorted, with the summed weight `w_ij` of all the
//! triangles beside edge `ij`. One pass over the triangles builds it, without the global sort
//! of a triplet list; the same rows then give the graph for the fill-reducing order, the count
//! of negative (cotangent) weights and the lower triangle of the free-vertex system, whose
//! columns come out sorted. `tutte` and `minimal_surface` build it while the mesh connectivity
//! is being built on the other core.

use super::laplacian::corner_cotangents;
use super::triangles::corner_row_starts;
use cgnodes_linalg::laplace::LaplaceRows;
use cgnodes_linalg::nested_dissection::{nested_dissection, Dissection, ND_MIN_ROWS};

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
    ) -> Result<LaplacianRows, super::laplacian::LaplacianError> {
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
        // two entries (both edges at the corner) per corner
        let count = corner_row_starts(n, triangles, 2);
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

    /// The rows as the symmetric Laplacian of `linalg::laplace` (for its Dirichlet solves).
    pub fn laplace(&self) -> LaplaceRows<'_> {
        LaplaceRows {
            start: &self.start,
            col: &self.col,
            weight: &self.weight,
        }
    }

    /// Elimination order of all vertices by geometric nested dissection (see
    /// `linalg/nested_dissection.rs`), for the factorization of any free-vertex block.
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

#[cfg(test)]
mod tests {
    use super::super::laplacian::cotangent_weights;
    use super::super::triangles::grid_triangles;
    use super::*;
    use cgnodes_linalg::laplace::solve_dirichlet;
    use cgnodes_linalg::laplace_weights::solve_dirichlet_weights;

    /// A 6 x 6 grid of squares split into triangles (vertex `(i, j)` is `7 j + i`), jittered
    /// and bent so the weights differ.
    fn grid() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let p = (0..49)
            .map(|v| {
                let (i, j) = (v % 7, v / 7);
                let jitter = ((i * 7 + j * 13) % 5) as f64 * 0.03;
                [i as f64 + jitter, j as f64 - jitter, 0.1 * (i * j) as f64]
            })
            .collect();
        (p, grid_triangles(6, 6))
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
        let a = solve_dirichlet_weights(&w, &fixed, true).unwrap();
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
            let b = solve_dirichlet(rows.laplace(), &fixed, ord).unwrap();
            for (x, y) in a.iter().zip(&b) {
                assert!((x[0] - y[0]).abs() < 1e-12 && (x[1] - y[1]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn a_free_vertex_without_weights_is_an_error() {
        let (p, t) = grid();
        let rows = LaplacianRows::uniform(p.len() + 1, &t);
        let mut fixed: Vec<Option<[f64; 1]>> = vec![Some([0.0]); p.len() + 1];
        fixed[p.len()] = None; // a vertex no triangle uses, left free
        let e = solve_dirichlet(rows.laplace(), &fixed, None).unwrap_err();
        assert!(
            e.message.contains("no usable edge weights"),
            "{}",
            e.message
        );
    }
}
