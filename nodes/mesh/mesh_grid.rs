//! `mesh_grid`: a flat rectangular grid of quads or triangles, centred at a point, like the
//! course's `grid10x10.usda` (which spans -1..1 in the xy plane, 11 x 11 vertices).

use crate::prelude::*;

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
) -> Result<Mesh, String> {
    let p = GridPlane::from_name(plane)
        .ok_or_else(|| format!("unknown plane '{plane}' (xy, xz or yz)"))?;
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
) -> Result<Mesh, String> {
    if cells_u == 0 || cells_v == 0 {
        return Err("a grid needs at least one cell along each side".into());
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
    Mesh::new(pos, counts, idx).map_err(|e| e.to_string())
}

/// The bytes a `cells_u x cells_v` grid takes while it is built: 24 per vertex (position),
/// per face 8 (count and offset) and per corner 8 (the index and its copy during the build).
/// An estimate for `ExecContext::reserve_bytes`, saturating instead of overflowing.
pub fn grid_mesh_bytes(cells_u: u64, cells_v: u64, triangles: bool) -> u64 {
    use crate::node::bytes_of;
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

fn declare(b: &mut NodeBuilder) {
    b.doc("A flat rectangular grid mesh (cloth), like the course's gridNxN.usda.");
    b.add_input::<i64>("cells_u")
        .default(10i64)
        .range(1.0, 4096.0)
        .doc("Cells along the first axis of the plane.");
    b.add_input::<i64>("cells_v")
        .default(10i64)
        .range(1.0, 4096.0)
        .doc("Cells along the second axis of the plane.");
    b.add_input::<[f64; 2]>("size")
        .default([2.0, 2.0])
        .doc("Extent along the two axes.");
    b.add_choice::<GridPlane>("plane");
    b.add_input::<[f64; 3]>("center").default([0.0, 0.0, 0.0]);
    b.add_input::<bool>("triangles")
        .default(true)
        .doc("Split each quad into two triangles (as the course grids are).");
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let cu: i64 = ctx.input("cells_u")?;
    let cv: i64 = ctx.input("cells_v")?;
    let size: [f64; 2] = ctx.input("size")?;
    if size.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
        return Err(NodeError::invalid("size", "both extents must be positive"));
    }
    let plane = ctx.choice::<GridPlane>("plane")?;
    let center: [f64; 3] = ctx.input("center")?;
    let tri: bool = ctx.input("triangles")?;
    let (cu, cv) = (cu.max(1), cv.max(1));
    ctx.reserve_bytes(
        "cells_u",
        &format!("a {cu}x{cv} grid"),
        grid_mesh_bytes(cu as u64, cv as u64, tri),
    )?;
    let m = grid_mesh_in(
        cu.max(1) as usize,
        cv.max(1) as usize,
        size,
        plane,
        center,
        tri,
    )
    .map_err(|e| NodeError::invalid("plane", e))?;
    ctx.set_output("mesh", m);
    Ok(())
}

/// Registers `mesh_grid`.
pub fn register(r: &mut Registry) {
    r.add("mesh_grid", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_matches_course_layout() {
        let m = grid_mesh(10, 10, [2.0, 2.0], "xy", [0.0; 3], true).unwrap();
        assert_eq!(m.num_vertices(), 121);
        assert_eq!(m.num_faces(), 200);
        assert_eq!(m.positions[0], [-1.0, -1.0, 0.0]);
        assert_eq!(m.positions[120], [1.0, 1.0, 0.0]);
        // A disk: Euler characteristic 1.
        assert_eq!(m.topology().euler_characteristic(), 1);
        assert!(grid_mesh(0, 3, [1.0, 1.0], "xy", [0.0; 3], false).is_err());
    }
}
