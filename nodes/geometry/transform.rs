//! Affine transforms of meshes: points, normals, and face order when the transform mirrors.

use cgnodes_api::prelude::*;
use cgnodes_formats::usda::reverse_faces;
use cgnodes_formats::usda::transform::{transform_normals, transform_points};
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

/// Why a transform cannot be built or applied.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TransformError {
    /// A zero (or non-finite) rotation axis with a non-zero angle.
    #[error("the rotation axis is zero")]
    ZeroAxis,
    /// The composed matrix has a NaN or infinite entry.
    #[error("the transform is not finite")]
    NonFinite,
    /// A singular linear part applied to a mesh with normals.
    #[error("the transform is singular, so normals cannot follow it")]
    Singular,
}

/// The transform nodes report errors as text: the message unchanged.
impl From<TransformError> for String {
    fn from(e: TransformError) -> String {
        e.to_string()
    }
}

impl Transform {
    /// The 4x4 matrix acting on column vectors `(x, y, z, 1)`; `Err` when the axis is zero
    /// while the angle is not.
    pub fn matrix(&self) -> Result<Matrix4<f64>, TransformError> {
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
                return Err(TransformError::ZeroAxis);
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
            return Err(TransformError::NonFinite);
        }
        Ok(out)
    }
}

/// `mesh` with `m` (column-vector convention) applied to its points and normals; faces are
/// reversed when `m` mirrors. `Err` when `m`'s linear part is singular and the mesh has normals.
pub fn transform_mesh(mesh: &Mesh, m: &Matrix4<f64>) -> Result<Mesh, TransformError> {
    let row = m.transpose(); // the usda helpers take USD's row-vector matrices
    let mut out = mesh.clone();
    transform_points(&row, &mut out.positions);
    if let Some(n) = out.normals.as_mut() {
        transform_normals(&row, &mut n.values).ok_or(TransformError::Singular)?;
    }
    let det = m.fixed_view::<3, 3>(0, 0).determinant();
    if det < 0.0 {
        reverse_faces(&mut out);
    }
    Ok(out)
}
