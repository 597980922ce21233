//! `create_grid`: Framework3D's `geom_create_grid` (Create Grid) as the course builds it: a
//! square of `resolution x resolution` quads in the x = 0 plane spanning [0, size] in y and z,
//! with texture coordinates (i / resolution, j / resolution). (`mesh_grid` is the centred,
//! general grid; this one keeps the framework's layout so imported graphs place it alike.)

use cgnodes_api::prelude::*;

/// Why the course's grid cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum CreateGridError {
    /// A resolution of 0.
    #[error("the grid needs at least one cell")]
    NoCells,
    /// The quads do not make a valid mesh (non-finite positions).
    #[error("{0}")]
    Mesh(#[from] MeshError),
}

/// The course's grid: vertex `(i, j)` (i along y, j along z) has index `i (r + 1) + j`,
/// position `(0, size i / r, size j / r)` and UV `(i / r, j / r)`; quad `(i, j)` is
/// `[i n + j, i n + j + 1, (i + 1) n + j + 1, (i + 1) n + j]` with `n = r + 1`.
pub fn create_grid(resolution: usize, size: f64) -> Result<Mesh, CreateGridError> {
    if resolution == 0 {
        return Err(CreateGridError::NoCells);
    }
    let n = resolution + 1;
    let r = resolution as f64;
    let mut pos = Vec::with_capacity(n * n);
    let mut uv = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            pos.push([0.0, size * i as f64 / r, size * j as f64 / r]);
            uv.push([i as f64 / r, j as f64 / r]);
        }
    }
    let mut idx = Vec::with_capacity(4 * resolution * resolution);
    for i in 0..resolution {
        for j in 0..resolution {
            let a = (i * n + j) as u32;
            let b = ((i + 1) * n + j) as u32;
            idx.extend([a, a + 1, b + 1, b]);
        }
    }
    let mut m = Mesh::new(pos, vec![4; resolution * resolution], idx)?;
    m.uvs = Some(Attribute {
        domain: Domain::Vertex,
        values: uv,
    });
    Ok(m)
}

fn declare(b: &mut NodeBuilder) {
    b.doc("A quad grid in the x = 0 plane spanning [0, size] in y and z, with UVs (Framework3D's Create Grid).");
    b.add_input::<i64>("resolution")
        .default(2i64)
        .range(1.0, 4096.0)
        .doc("Quads along each side.");
    b.add_input::<f64>("size")
        .default(1.0)
        .range(0.0, 1e6)
        .doc("Side length.");
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let r: i64 = ctx.input("resolution")?;
    if !(1..=4096).contains(&r) {
        return Err(NodeError::invalid(
            "resolution",
            "must be between 1 and 4096",
        ));
    }
    let size: f64 = ctx.input("size")?;
    if !(size.is_finite() && size > 0.0) {
        return Err(NodeError::invalid("size", "must be positive"));
    }
    let m = create_grid(r as usize, size)
        .map_err(|e| NodeError::invalid("resolution", e.to_string()))?;
    ctx.set_output("mesh", m);
    Ok(())
}

/// Registers `create_grid`.
pub fn register(r: &mut Registry) {
    r.add("create_grid", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn follows_the_course_layout() {
        let m = create_grid(2, 3.0).unwrap();
        assert_eq!(m.num_vertices(), 9);
        assert_eq!(m.num_faces(), 4);
        // Vertex (i=1, j=2) is index 5 at (0, 1.5, 3) with UV (0.5, 1).
        assert_eq!(m.positions[5], [0.0, 1.5, 3.0]);
        assert_eq!(m.uvs.as_ref().unwrap().values[5], [0.5, 1.0]);
        assert_eq!(m.face(3), &[4, 5, 8, 7]);
        assert_eq!(m.topology().euler_characteristic(), 1);
        assert!(create_grid(0, 1.0).is_err());
    }
}
