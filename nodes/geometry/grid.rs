//! A regular grid of quads or triangles in a coordinate plane (`mesh_grid`, cloth set-ups).

use cgnodes_api::prelude::*;

/// The coordinate plane a grid lies in (the `plane` socket).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridPlane {
    /// u along x, v along y.
    Xy,
    /// u along x, v along z.
    Xz,
    /// u along y, v along z.
    Yz,
}

impl GridPlane {
    /// The coordinate indices of the u and v axes.
    pub fn axes(self) -> (usize, usize) {
        match self {
            GridPlane::Xy => (0, 1),
            GridPlane::Xz => (0, 2),
            GridPlane::Yz => (1, 2),
        }
    }
}

impl Choice for GridPlane {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("xy", GridPlane::Xy),
        ("xz", GridPlane::Xz),
        ("yz", GridPlane::Yz),
    ];
}

/// A grid of `cells_u x cells_v` cells spanning `size` in the plane `plane` ("xy", "xz" or
/// "yz"), centred at `center`: `grid_mesh_in` with the plane given by name.
pub fn grid_mesh(
    cells_u: usize,
    cells_v: usize,
    size: [f64; 2],
    plane: &str,
    center: [f64; 3],
    triangles: bool,
) -> Result<Mesh, GridError> {
    let p =
        GridPlane::from_name(plane).ok_or_else(|| GridError::UnknownPlane(plane.to_string()))?;
    grid_mesh_in(cells_u, cells_v, size, p, center, triangles)
}

/// A grid of `cells_u x cells_v` cells spanning `size` in `plane`, centred at `center`.
/// Vertex `(i, j)` (i along u) has index `j * (cells_u + 1) + i`. Quads are split along the
/// `(i, j)-(i+1, j+1)` diagonal when `triangles` is set.
pub fn grid_mesh_in(
    cells_u: usize,
    cells_v: usize,
    size: [f64; 2],
    plane: GridPlane,
    center: [f64; 3],
    triangles: bool,
) -> Result<Mesh, GridError> {
    if cells_u == 0 || cells_v == 0 {
        return Err(GridError::NoCells);
    }
    let (au, av) = plane.axes();
    let (nu, nv) = (cells_u + 1, cells_v + 1);
    let mut pos = Vec::with_capacity(nu * nv);
    for j in 0..nv {
        for i in 0..nu {
            let mut p = center;
            p[au] += size[0] * (i as f64 / cells_u as f64 - 0.5);
            p[av] += size[1] * (j as f64 / cells_v as f64 - 0.5);
            pos.push(p);
        }
    }
    let (counts, idx) = if triangles {
        let tris = grid_triangles(cells_u, cells_v);
        (vec![3; tris.len()], tris.into_iter().flatten().collect())
    } else {
        let mut idx = Vec::with_capacity(4 * cells_u * cells_v);
        for j in 0..cells_v {
            for i in 0..cells_u {
                let a = (j * nu + i) as u32;
                idx.extend([a, a + 1, a + 1 + nu as u32, a + nu as u32]);
            }
        }
        (vec![4; cells_u * cells_v], idx)
    };
    Ok(Mesh::new(pos, counts, idx)?)
}

/// Why a grid cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum GridError {
    /// A plane name other than xy, xz or yz.
    #[error("unknown plane '{0}' (xy, xz or yz)")]
    UnknownPlane(String),
    /// Zero cells along a side.
    #[error("a grid needs at least one cell along each side")]
    NoCells,
    /// The positions do not make a valid mesh (non-finite size or centre).
    #[error("{0}")]
    Mesh(#[from] MeshError),
}

/// The mesh nodes report errors as text: the message unchanged.
impl From<GridError> for String {
    fn from(e: GridError) -> String {
        e.to_string()
    }
}

/// The bytes a `cells_u x cells_v` grid takes while it is built: 24 per vertex (position),
/// per face 8 (count and offset) and per corner 8 (the index and its copy during the build).
/// An estimate for `ExecContext::reserve_bytes`, saturating instead of overflowing.
pub fn grid_mesh_bytes(cells_u: u64, cells_v: u64, triangles: bool) -> u64 {
    use cgnodes_api::node::bytes_of;
    let vertices = bytes_of(&[cells_u.saturating_add(1), cells_v.saturating_add(1)]);
    let cells = bytes_of(&[cells_u, cells_v]);
    let (faces, corners) = if triangles {
        (bytes_of(&[cells, 2]), bytes_of(&[cells, 6]))
    } else {
        (cells, bytes_of(&[cells, 4]))
    };
    bytes_of(&[vertices, 24])
        .saturating_add(bytes_of(&[faces, 8]))
        .saturating_add(bytes_of(&[corners, 8]))
}
