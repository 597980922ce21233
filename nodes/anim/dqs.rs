//! Dual-quaternion skinning (Kavan, Collins, Žára, O'Sullivan 2007, "Skinning with dual
//! quaternions"): each joint's rigid skinning transform becomes a unit dual quaternion, a
//! vertex blends its joints' dual quaternions linearly (signs flipped onto the hemisphere of
//! the vertex's first influence, §4 "antipodality") and normalizes the sum (DLB, eq. 4), and
//! the result moves the point rigidly. Unlike linear blending this cannot shrink a twisted
//! limb (the candy-wrapper artefact). Scale and shear in a joint's transform are dropped
//! (its nearest rotation is used); the geometry bind transform is applied before and the
//! skeleton placement after, as in `lbs`.

use super::lbs::Influences;
use cgnodes_formats::usda::transform::Mat4;
use nalgebra::{
    DualQuaternion, Matrix3, Point3, Quaternion, Rotation3, RowVector3, Translation3,
    UnitDualQuaternion, UnitQuaternion, Vector3,
};
use rayon::prelude::*;

/// The unit dual quaternion of a row-vector transform `m` (`p' = p A + t`): rotation `Aᵀ`
/// (the nearest rotation when `A` is not one), translation `t`; and how far `A` is from a
/// rotation (Frobenius norm of `AᵀA - I`).
pub fn to_dual_quaternion(m: &Mat4) -> (UnitDualQuaternion<f64>, f64) {
    let a: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    let r = a.transpose();
    let off = (a.transpose() * a - Matrix3::identity()).norm();
    let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_eps(
        &r,
        1e-15,
        100,
        Rotation3::identity(),
    ));
    let t = Translation3::new(m[(3, 0)], m[(3, 1)], m[(3, 2)]);
    (UnitDualQuaternion::from_parts(t, rot), off)
}

/// The normalized blend of a vertex's dual quaternions (DLB).
#[inline(always)]
fn blend(v: usize, inf: &Influences, dq: &[DualQuaternion<f64>]) -> UnitDualQuaternion<f64> {
    let k = inf.count;
    let zero = Quaternion::new(0.0, 0.0, 0.0, 0.0);
    let mut b = DualQuaternion::from_real_and_dual(zero, zero);
    let mut pivot: Option<Quaternion<f64>> = None;
    for e in v * k..v * k + k {
        let w = inf.weights[e];
        if w == 0.0 {
            continue;
        }
        let q = &dq[inf.indices[e] as usize];
        let p = *pivot.get_or_insert(q.real);
        let s = if p.coords.dot(&q.real.coords) < 0.0 {
            -w
        } else {
            w
        };
        b.real += q.real * s;
        b.dual += q.dual * s;
    }
    if b.real.norm() < 1e-300 {
        return UnitDualQuaternion::identity();
    }
    UnitDualQuaternion::new_normalize(b)
}

/// The inverse transpose of `m`'s linear part (for normals), `None` when singular.
fn normal_matrix(m: &Mat4) -> Option<Matrix3<f64>> {
    let a: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    a.try_inverse().map(|i| i.transpose())
}

fn is_identity(m: &Mat4) -> bool {
    *m == Mat4::identity()
}

fn row_apply(m: &Mat4, p: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|c| p[0] * m[(0, c)] + p[1] * m[(1, c)] + p[2] * m[(2, c)] + m[(3, c)])
}

/// Normals to skin and, for per-corner normals, the vertex of each (see `lbs_normals`).
pub type NormalsIn<'a> = (&'a [[f64; 3]], Option<&'a [u32]>);

/// What `dqs` returns: points, normals, and the largest departure of a joint's transform
/// from a rigid one.
pub type DqsOut = (Vec<[f64; 3]>, Option<Vec<[f64; 3]>>, f64);

/// Skins `points` and (optionally) normals by DQS. `skinning` holds the joints' skinning
/// transforms `bind_j⁻¹ skel_j`; `geom_bind` is applied to the points first and `post` to the
/// result. `vertex_of` maps normals to vertices as in `lbs_normals`. Influences must have
/// passed `check_influences`. Returns the points, the normals, and the largest departure of a
/// joint transform from a rigid one (see `to_dual_quaternion`).
pub fn dqs(
    points: &[[f64; 3]],
    normals: Option<NormalsIn>,
    inf: &Influences,
    geom_bind: &Mat4,
    skinning: &[Mat4],
    post: &Mat4,
) -> DqsOut {
    let mut off: f64 = 0.0;
    let dq: Vec<DualQuaternion<f64>> = skinning
        .iter()
        .map(|m| {
            let (q, o) = to_dual_quaternion(m);
            off = off.max(o);
            *q.dual_quaternion()
        })
        .collect();
    let (g_id, w_id) = (is_identity(geom_bind), is_identity(post));
    let mut out = vec![[0.0; 3]; points.len()];
    out.par_iter_mut()
        .with_min_len(2048)
        .enumerate()
        .for_each(|(v, o)| {
            let p = if g_id {
                points[v]
            } else {
                row_apply(geom_bind, points[v])
            };
            let q = blend(v, inf, &dq);
            let r = q.transform_point(&Point3::new(p[0], p[1], p[2]));
            let r = [r.x, r.y, r.z];
            *o = if w_id { r } else { row_apply(post, r) };
        });
    let normals = normals.map(|(ns, vertex_of)| {
        // Singular placements leave normals as they are.
        let g = normal_matrix(geom_bind).unwrap_or_else(Matrix3::identity);
        let w = normal_matrix(post).unwrap_or_else(Matrix3::identity);
        let mut out = vec![[0.0; 3]; ns.len()];
        out.par_iter_mut()
            .with_min_len(2048)
            .enumerate()
            .for_each(|(i, o)| {
                let v = vertex_of.map_or(i, |m| m[i] as usize);
                let n = RowVector3::from(ns[i]) * g;
                let q = blend(v, inf, &dq);
                let r = q
                    .rotation()
                    .transform_vector(&Vector3::new(n[0], n[1], n[2]));
                let r = RowVector3::new(r.x, r.y, r.z) * w;
                let len = r.norm();
                *o = if len > 0.0 {
                    [r[0] / len, r[1] / len, r[2] / len]
                } else {
                    ns[i]
                };
            });
        out
    });
    (out, normals, off)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lbs::{joint_matrices, lbs_points};
    use crate::pose::make_transform;

    #[test]
    fn one_rigid_joint_equals_lbs() {
        let (s, c) = (0.3f64.sin(), 0.3f64.cos());
        let m = make_transform([1.0, -2.0, 0.5], [c, 0.0, s, 0.0], [1.0; 3]);
        let inf = Influences {
            count: 1,
            indices: &[0, 0],
            weights: &[1.0, 1.0],
        };
        let pts = [[0.3, 0.4, 0.5], [-1.0, 2.0, 3.0]];
        let id = Mat4::identity();
        let (d, _, off) = dqs(&pts, None, &inf, &id, &[m], &id);
        let l = lbs_points(&pts, &inf, &joint_matrices(&id, &[m], &id));
        assert!(off < 1e-12);
        for (a, b) in d.iter().zip(&l) {
            for k in 0..3 {
                assert!((a[k] - b[k]).abs() < 1e-12, "{a:?} {b:?}");
            }
        }
    }

    #[test]
    fn half_twist_keeps_the_distance_to_the_axis() {
        // Two joints, one turned 180 degrees about z: LBS collapses a point at radius 1 onto
        // the axis, DQS turns it by 90 degrees and keeps radius 1 (Kavan et al., Fig. 2).
        let id = Mat4::identity();
        let half = make_transform([0.0; 3], [0.0, 0.0, 0.0, 1.0], [1.0; 3]);
        let inf = Influences {
            count: 2,
            indices: &[0, 1],
            weights: &[0.5, 0.5],
        };
        let (d, _, _) = dqs(&[[1.0, 0.0, 0.0]], None, &inf, &id, &[id, half], &id);
        let l = lbs_points(&[[1.0, 0.0, 0.0]], &inf, &[id, half]);
        let r = |p: [f64; 3]| (p[0] * p[0] + p[1] * p[1]).sqrt();
        assert!((r(d[0]) - 1.0).abs() < 1e-12 && r(l[0]) < 1e-12);
    }
}
