//! Triangle lists of meshes: the fan triangulation of polygons the parameterization nodes
//! work on, and the triangulated regular grid of tests and examples.

use crate::prelude::*;

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
    }
}
