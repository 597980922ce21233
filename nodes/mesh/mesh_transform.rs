//! `mesh_transform`: an affine transform applied to a mesh's points (Framework3D's
//! `geom_apply_transform_geom`): scale, Euler rotations in degrees, an axis-angle rotation,
//! a translation, and an optional 4x4 matrix. Normals go through the inverse transpose, and
//! a transform that mirrors (negative determinant) reverses the faces so they stay
//! counter-clockwise.
//!
//! Order, as Framework3D builds it with USD's row-vector matrices (`v * Rx * Ry * Rz * S * T`):
//! `p' = M * T * S * R_axis * Rz * Ry * Rx * p` in column vectors, `M` the optional matrix.

use cgnodes_api::prelude::*;
pub use cgnodes_geometry::transform::*;

fn declare(b: &mut NodeBuilder) {
    b.doc("Moves a mesh: scale, Euler rotations (degrees), an axis-angle rotation, translation, then an optional 4x4 matrix.");
    b.add_input::<Mesh>("mesh");
    b.add_input::<[f64; 3]>("translate").default([0.0; 3]);
    b.add_input::<[f64; 3]>("rotate")
        .default([0.0; 3])
        .doc("Degrees about x, then y, then z (Framework3D's Rotate X, Y, Z).");
    b.add_input::<[f64; 3]>("axis")
        .default([0.0, 0.0, 1.0])
        .doc("Axis of the `angle` rotation.");
    b.add_input::<f64>("angle")
        .default(0.0)
        .doc("Degrees about `axis`, after the Euler rotations.");
    b.add_input::<[f64; 3]>("scale")
        .default([1.0; 3])
        .doc("Scale along x, y, z, applied after the rotations (as Framework3D does).");
    b.add_input::<Vec<f64>>("matrix").optional().doc(
        "16 numbers, a 4x4 matrix as USD writes it (rows; translation in the fourth row), applied last.",
    );
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let matrix = match ctx.input_opt::<Vec<f64>>("matrix")? {
        None => None,
        Some(v) => Some(<[f64; 16]>::try_from(v.as_slice()).map_err(|_| {
            NodeError::invalid(
                "matrix",
                format!("{} numbers; a 4x4 matrix has 16", v.len()),
            )
        })?),
    };
    let t = Transform {
        translate: ctx.input("translate")?,
        rotate: ctx.input("rotate")?,
        axis: ctx.input("axis")?,
        angle: ctx.input("angle")?,
        scale: ctx.input("scale")?,
        matrix,
    };
    let m = t.matrix().map_err(|e| NodeError::invalid("axis", e))?;
    let out = transform_mesh(&mesh, &m).map_err(|e| NodeError::invalid("scale", e))?;
    ctx.set_output("mesh", out);
    Ok(())
}

/// Registers `mesh_transform`.
pub fn register(r: &mut Registry) {
    r.add("mesh_transform", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn apply(t: &Transform, p: [f64; 3]) -> [f64; 3] {
        let m = Mesh::new(vec![p], Vec::new(), Vec::new()).unwrap();
        transform_mesh(&m, &t.matrix().unwrap()).unwrap().positions[0]
    }

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        (0..3).all(|c| (a[c] - b[c]).abs() < 1e-12)
    }

    #[test]
    fn framework3d_order_scale_after_rotation_then_translate() {
        // Rotate X 90: (0, 1, 0) -> (0, 0, 1); scale z by 2 -> (0, 0, 2); translate +x.
        let t = Transform {
            rotate: [90.0, 0.0, 0.0],
            scale: [1.0, 1.0, 2.0],
            translate: [1.0, 0.0, 0.0],
            ..Default::default()
        };
        assert!(close(apply(&t, [0.0, 1.0, 0.0]), [1.0, 0.0, 2.0]));
        // X before Z: (0, 1, 0) -X90-> (0, 0, 1) -Z90-> (0, 0, 1); Z first would give (-1, 0, 0).
        let t = Transform {
            rotate: [90.0, 0.0, 90.0],
            ..Default::default()
        };
        assert!(close(apply(&t, [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]));
    }

    #[test]
    fn axis_angle_and_usd_matrix() {
        // 120 degrees about (1, 1, 1) cycles the axes: x -> y.
        let t = Transform {
            axis: [1.0, 1.0, 1.0],
            angle: 120.0,
            ..Default::default()
        };
        assert!(close(apply(&t, [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0]));
        // A USD matrix with translation (0, 0, 2) in its fourth row, as arm.usda's bind
        // transforms are written.
        let mut m = [0.0; 16];
        for i in 0..4 {
            m[i * 5] = 1.0;
        }
        m[14] = 2.0;
        let t = Transform {
            matrix: Some(m),
            ..Default::default()
        };
        assert!(close(apply(&t, [1.0, 1.0, 1.0]), [1.0, 1.0, 3.0]));
        let bad = Transform {
            axis: [0.0; 3],
            angle: 10.0,
            ..Default::default()
        };
        assert!(bad.matrix().is_err());
    }

    #[test]
    fn mirroring_reverses_faces_and_flips_normals() {
        let mut m = Mesh::from_triangles(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            &[[0, 1, 2]],
        )
        .unwrap();
        m.normals = Some(Attribute {
            domain: Domain::Vertex,
            values: vec![[0.0, 0.0, 1.0]; 3],
        });
        let t = Transform {
            scale: [1.0, 1.0, -1.0],
            ..Default::default()
        };
        let out = transform_mesh(&m, &t.matrix().unwrap()).unwrap();
        assert_eq!(out.face(0), &[2, 1, 0]);
        assert!(close(out.normals.unwrap().values[0], [0.0, 0.0, -1.0]));
    }
}
