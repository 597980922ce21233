//! `mesh_grid`: a flat rectangular grid of quads or triangles, centred at a point, like the
//! course's `grid10x10.usda` (which spans -1..1 in the xy plane, 11 x 11 vertices).

use cgnodes_api::prelude::*;
pub use cgnodes_geometry::grid::*;

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
