//! Triangle lists of meshes: the fan triangulation of polygons the parameterization nodes
//! work on, the triangulated regular grid of tests and examples, and per-vertex lists of
//! triangle corners in compressed rows.

use cgnodes_api::prelude::*;

/// Splits every polygon into a fan of triangles from its first corner (`Mesh::fan_triangles`,
/// named here for the parameterization code that calls it on every mesh).
pub fn fan_triangles(mesh: &Mesh) -> Vec<[u32; 3]> {
    mesh.fan_triangles()
}

/// The triangulated regular grid (`Topology`'s neighbour in `src/types`), named here too.
pub use cgnodes_api::types::{grid_triangles, grid_triangles_with};

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
        let (start, list) = cgnodes_api::types::Topology::vertex_triangles(6, &t);
        assert_eq!(start, [0, 2, 5, 6, 7, 10, 12]);
        assert_eq!(&list[start[4]..start[5]], [0, 1, 3]);
    }
}
