//! `mesh_transform`: an affine transform applied to a mesh's points (Framework3D's
//! `geom_apply_transform_geom`): scale, Euler rotations in degrees, an axis-angle rotation,
//! a translation, and an optional 4x4 matrix. Normals go through the inverse transpose, and
//! a transform that mirrors (negative determinant) reverses the faces so they stay
//! counter-clockwise.
//!
//! Order, as Framework3D builds it with USD's row-vector matrices (`v * Rx * Ry * Rz * S * T`):
//! `p' = M * T * S * R_axis * Rz * Ry * Rx * p` in column vectors, `M` the optional matrix.

use crate::nodes::mesh::usda::reverse_faces;
use crate::nodes::mesh::usda::transform::{transform_normals, transform_points};
use crate::prelude::*;
use nalgebra::{Matrix4, Rotation3, Unit, Vector3};

/// The parts of a `mesh_transform`.
#[derive(Clone, Debug, PartialEq)]
pub struct Transform {
    /// Translation.
    pub translate: [f64; 3],
    /// Rotations about x, then y, then z, in degrees.
    pub rotate: [f64; 3],
    /// Rotation axis (any length but zero) for `angle`.
    pub axis: [f64; 3],
    /// Rotation about `axis` in degrees, after the Euler rotations.
    pub angle: f64,
    /// Scale along x, y, z, after the rotations.
    pub scale: [f64; 3],
    /// A last 4x4 matrix in USD's layout (row vectors: translation in the fourth row).
    pub matrix: Option<[f64; 16]>,
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            translate: [0.0; 3],
            rotate: [0.0; 3],
            axis: [0.0, 0.0, 1.0],
            angle: 0.0,
            scale: [1.0; 3],
            matrix: None,
        }
    }
}

impl Transform {
    /// The 4x4 matrix acting on column vectors `(x, y, z, 1)`; `Err` when the axis is zero
    /// while the angle is not.
    pub fn matrix(&self) -> Result<Matrix4<f64>, String> {
        let rot = |axis: Vector3<f64>, deg: f64| {
            Rotation3::from_axis_angle(&Unit::new_normalize(axis), deg.to_radians())
                .to_homogeneous()
        };
        let euler = rot(Vector3::z(), self.rotate[2])
            * rot(Vector3::y(), self.rotate[1])
            * rot(Vector3::x(), self.rotate[0]);
        let aa = if self.angle == 0.0 {
            Matrix4::identity()
        } else {
            let a = Vector3::from(self.axis);
            if a.norm() == 0.0 || !a.norm().is_finite() {
                return Err("the rotation axis is zero".into());
            }
            rot(a, self.angle)
        };
        let s = Matrix4::new_nonuniform_scaling(&Vector3::from(self.scale));
        let t = Matrix4::new_translation(&Vector3::from(self.translate));
        // USD writes a matrix for row vectors; for column vectors it is the transpose.
        let m = match self.matrix {
            Some(v) => Matrix4::from_row_slice(&v).transpose(),
            None => Matrix4::identity(),
        };
        let out = m * t * s * aa * euler;
        if out.iter().any(|x| !x.is_finite()) {
            return Err("the transform is not finite".into());
        }
        Ok(out)
    }
}

/// `mesh` with `m` (column-vector convention) applied to its points and normals; faces are
/// reversed when `m` mirrors. `Err` when `m`'s linear part is singular and the mesh has normals.
pub fn transform_mesh(mesh: &Mesh, m: &Matrix4<f64>) -> Result<Mesh, String> {
    let row = m.transpose(); // the usda helpers take USD's row-vector matrices
    let mut out = mesh.clone();
    transform_points(&row, &mut out.positions);
    if let Some(n) = out.normals.as_mut() {
        transform_normals(&row, &mut n.values)
            .ok_or("the transform is singular, so normals cannot follow it")?;
    }
    let det = m.fixed_view::<3, 3>(0, 0).determinant();
    if det < 0.0 {
        reverse_faces(&mut out);
    }
    Ok(out)
}

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
            NodeError::invalid("matrix", format!("{} numbers; a 4x4 matrix has 16", v.len()))
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
