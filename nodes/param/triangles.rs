//! Triangle lists of meshes: the fan triangulation of polygons the parameterization nodes
//! work on, the triangulated regular grid of tests and examples, and per-vertex lists of
//! triangle corners in compressed rows.

use crate::prelude::*;

/// Splits every polygon into a fan of triangles from its first corner (`Mesh::fan_triangles`,
/// named here for the parameterization code that calls it on every mesh).
pub fn fan_triangles(mesh: &Mesh) -> Vec<[u32; 3]> {
    mesh.fan_triangles()
}

/// The triangles of a grid of `cells_u x cells_v` squares, each split along its
/// `(i, j)-(i+1, j+1)` diagonal, counter-clockwise when `i` runs along x and `j` along y.
/// Vertex `(i, j)` is `id(i, j)` for `i` in `0..=cells_u`, `j` in `0..=cells_v` (row by row:
/// `grid_triangles`); the squares come row by row.
pub fn grid_triangles_with(
    cells_u: usize,
    cells_v: usize,
    id: impl Fn(usize, usize) -> u32,
) -> Vec<[u32; 3]> {
    let mut t = Vec::with_capacity(2 * cells_u * cells_v);
    for j in 0..cells_v {
        for i in 0..cells_u {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    t
}

/// `grid_triangles_with` for the vertices numbered row by row, `(i, j)` at
/// `j (cells_u + 1) + i` (the numbering of the `mesh_grid` node).
pub fn grid_triangles(cells_u: usize, cells_v: usize) -> Vec<[u32; 3]> {
    grid_triangles_with(cells_u, cells_v, |i, j| (j * (cells_u + 1) + i) as u32)
}

/// Row starts of compressed rows with `per_corner` entries for every triangle corner at a
/// vertex: row `v` is `start[v]..start[v + 1]`, `start[n]` the total. The counting pass of a
/// counting sort of per-vertex lists with several entries per corner (`LaplacianRows`).
pub fn corner_row_starts(n: usize, triangles: &[[u32; 3]], per_corner: usize) -> Vec<usize> {
    let mut start = vec![0usize; n + 1];
    for tri in triangles {
        for &v in tri {
            start[v as usize + 1] += per_corner;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    start
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_triangles_cover_each_square_once() {
        let t = grid_triangles(2, 1);
        assert_eq!(t.len(), 4);
        assert_eq!(t[0], [0, 1, 4]);
        assert_eq!(t[1], [0, 4, 3]);
        let m = Mesh::from_triangles(
            (0..6)
                .map(|v| [(v % 3) as f64, (v / 3) as f64, 0.0])
                .collect(),
            &t,
        )
        .unwrap();
        assert_eq!(fan_triangles(&m), t);
        assert_eq!(m.topology().boundary_loops.len(), 1);
        let (start, list) = crate::types::Topology::vertex_triangles(6, &t);
        assert_eq!(start, [0, 2, 5, 6, 7, 10, 12]);
        assert_eq!(&list[start[4]..start[5]], [0, 1, 3]);
    }
}
