//! The pose of a skeleton at a USD time code, computed as UsdSkel computes it: each animated
//! track sampled (translations and scales linearly, rotations by `GfSlerp`, held at the first
//! and last samples outside them), joint local transforms `scale * rotate * translate`
//! (`UsdSkelMakeTransform`), skeleton-space transforms down the hierarchy
//! (`skel_j = local_j * skel_parent`), and skinning transforms `inverse(bind_j) * skel_j`.
//! Matrices are USD's row-vector convention (`p' = p * M`), as `nodes::mesh::usda::transform`.

use cgnodes_api::types::{Skeleton, Track};
use cgnodes_formats::usda::skel::from_rows;
use cgnodes_formats::usda::transform::Mat4;

/// Why a pose cannot be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PoseError {
    /// A bind transform has no inverse.
    #[error("the bind transform of joint '{joint}' of Skeleton '{skeleton}' is not invertible")]
    SingularBind { skeleton: String, joint: String },
    /// The skeleton has no joints.
    #[error("Skeleton '{0}' has no joints")]
    NoJoints(String),
    /// A track's arrays do not match the animated joints.
    #[error("SkelAnimation '{anim}': a {what} sample has {got} values for {want} joints")]
    TrackLength {
        anim: String,
        what: &'static str,
        got: usize,
        want: usize,
    },
    /// A joint's parent comes after it.
    #[error("joint {0} of Skeleton '{1}' has a parent that does not come before it")]
    BadParent(usize, String),
}

/// The bracketing samples of `time` and the weight of the second: held at the ends.
fn bracket(times: &[f64], time: f64) -> (usize, usize, f64) {
    let n = times.len();
    if n <= 1 || time <= times[0] {
        return (0, 0, 0.0);
    }
    if time >= times[n - 1] {
        return (n - 1, n - 1, 0.0);
    }
    let hi = times.partition_point(|&t| t <= time);
    let lo = hi - 1;
    let a = (time - times[lo]) / (times[hi] - times[lo]);
    (lo, hi, a)
}

/// A vector track at `time` (linear interpolation, as `Usd_LinearInterpolator`).
pub fn sample_linear(t: &Track<[f64; 3]>, time: f64) -> Vec<[f64; 3]> {
    let (lo, hi, a) = bracket(&t.times, time);
    if lo == hi || a == 0.0 {
        return t.values[lo].clone();
    }
    t.values[lo]
        .iter()
        .zip(&t.values[hi])
        .map(|(x, y)| std::array::from_fn(|k| x[k] + a * (y[k] - x[k])))
        .collect()
}

/// USD's `GfSlerp(alpha, q0, q1)` on quaternions `(real, i, j, k)`: the shorter arc, linear
/// weights when the two are within 1e-5 of each other, and no renormalization (a file's
/// slightly non-unit quaternions stay as USD leaves them).
pub fn gf_slerp(alpha: f64, q0: [f64; 4], q1: [f64; 4]) -> [f64; 4] {
    let mut cos = (0..4).map(|k| q0[k] * q1[k]).sum::<f64>();
    let flip = cos < 0.0;
    if flip {
        cos = -cos;
    }
    let (s0, mut s1) = if 1.0 - cos > 1e-5 {
        let theta = cos.acos();
        let sin = theta.sin();
        (
            ((1.0 - alpha) * theta).sin() / sin,
            (alpha * theta).sin() / sin,
        )
    } else {
        (1.0 - alpha, alpha)
    };
    if flip {
        s1 = -s1;
    }
    std::array::from_fn(|k| s0 * q0[k] + s1 * q1[k])
}

/// A rotation track at `time` (slerp between samples).
pub fn sample_rotations(t: &Track<[f64; 4]>, time: f64) -> Vec<[f64; 4]> {
    let (lo, hi, a) = bracket(&t.times, time);
    if lo == hi || a == 0.0 {
        return t.values[lo].clone();
    }
    t.values[lo]
        .iter()
        .zip(&t.values[hi])
        .map(|(x, y)| gf_slerp(a, *x, *y))
        .collect()
}

/// `UsdSkelMakeTransform`: `scale * rotate * translate` in row-vector form, the rotation
/// matrix from the quaternion `(r, i, j, k)` by `GfMatrix3d::SetRotate`'s formula (which
/// assumes, and does not enforce, a unit quaternion).
pub fn make_transform(t: [f64; 3], q: [f64; 4], s: [f64; 3]) -> Mat4 {
    let (r, i, j, k) = (q[0], q[1], q[2], q[3]);
    let rot = [
        [
            1.0 - 2.0 * (j * j + k * k),
            2.0 * (i * j + k * r),
            2.0 * (k * i - j * r),
        ],
        [
            2.0 * (i * j - k * r),
            1.0 - 2.0 * (k * k + i * i),
            2.0 * (j * k + i * r),
        ],
        [
            2.0 * (k * i + j * r),
            2.0 * (j * k - i * r),
            1.0 - 2.0 * (j * j + i * i),
        ],
    ];
    let mut m = Mat4::identity();
    for a in 0..3 {
        for b in 0..3 {
            m[(a, b)] = rot[a][b] * s[a];
        }
        m[(3, a)] = t[a];
    }
    m
}

/// Joint local transforms at `time`: the animation's for the joints it drives, the rest
/// transforms for the others.
pub fn local_transforms(skel: &Skeleton, time: f64) -> Result<Vec<Mat4>, PoseError> {
    if skel.joints.is_empty() {
        return Err(PoseError::NoJoints(skel.prim.clone()));
    }
    let mut local: Vec<Mat4> = skel.joints.iter().map(|j| from_rows(&j.rest)).collect();
    if let Some(anim) = &skel.animation {
        let n = anim.joints.len();
        let t = sample_linear(&anim.translations, time);
        let r = sample_rotations(&anim.rotations, time);
        let s = anim.scales.as_ref().map(|s| sample_linear(s, time));
        let check = |what, got: usize| {
            if got != n {
                Err(PoseError::TrackLength {
                    anim: anim.prim.clone(),
                    what,
                    got,
                    want: n,
                })
            } else {
                Ok(())
            }
        };
        check("translation", t.len())?;
        check("rotation", r.len())?;
        if let Some(s) = &s {
            check("scale", s.len())?;
        }
        for (e, &j) in anim.joints.iter().enumerate() {
            let sc = s.as_ref().map_or([1.0; 3], |s| s[e]);
            if let Some(l) = local.get_mut(j) {
                *l = make_transform(t[e], r[e], sc);
            }
        }
    }
    Ok(local)
}

/// Skeleton-space joint transforms at `time` (`skel_j = local_j * skel_parent`).
pub fn skel_transforms(skel: &Skeleton, time: f64) -> Result<Vec<Mat4>, PoseError> {
    let local = local_transforms(skel, time)?;
    let mut out: Vec<Mat4> = Vec::with_capacity(local.len());
    for (i, (l, j)) in local.iter().zip(&skel.joints).enumerate() {
        out.push(match j.parent {
            None => *l,
            Some(p) if p < i => l * out[p],
            Some(_) => return Err(PoseError::BadParent(i, skel.prim.clone())),
        });
    }
    Ok(out)
}

/// Skinning transforms at `time`: `inverse(bind_j) * skel_j`, which take a point from its
/// bind-time skeleton-space position to its posed one.
pub fn skinning_transforms(skel: &Skeleton, time: f64) -> Result<Vec<Mat4>, PoseError> {
    let xf = skel_transforms(skel, time)?;
    skel.joints
        .iter()
        .zip(xf)
        .map(|(j, x)| {
            let inv = from_rows(&j.bind)
                .try_inverse()
                .filter(|m| m.iter().all(|v| v.is_finite()))
                .ok_or_else(|| PoseError::SingularBind {
                    skeleton: skel.prim.clone(),
                    joint: j.path.clone(),
                })?;
            Ok(inv * x)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use cgnodes_api::types::{Joint, SkelAnimation, IDENTITY_MATRIX};

    fn two_joints() -> Skeleton {
        let mut up = IDENTITY_MATRIX;
        up[3][2] = 2.0;
        Skeleton {
            prim: "/S".into(),
            joints: vec![
                Joint {
                    path: "A".into(),
                    parent: None,
                    bind: IDENTITY_MATRIX,
                    rest: IDENTITY_MATRIX,
                },
                Joint {
                    path: "A/B".into(),
                    parent: Some(0),
                    bind: up,
                    rest: up,
                },
            ],
            animation: None,
        }
    }

    #[test]
    fn rest_pose_gives_identity_skinning() {
        let s = two_joints();
        for m in skinning_transforms(&s, 3.0).unwrap() {
            assert!((m - Mat4::identity()).norm() < 1e-15);
        }
    }

    #[test]
    fn rotation_about_x_by_90_degrees_by_hand() {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let m = make_transform([1.0, 2.0, 3.0], [h, h, 0.0, 0.0], [1.0, 1.0, 1.0]);
        // Row-vector: y axis goes to z, z to -y; translation in the last row.
        let y = nalgebra::RowVector4::new(0.0, 1.0, 0.0, 0.0) * m;
        assert!((y[2] - 1.0).abs() < 1e-15 && y[1].abs() < 1e-15);
        let o = nalgebra::RowVector4::new(0.0, 0.0, 0.0, 1.0) * m;
        assert_eq!([o[0], o[1], o[2]], [1.0, 2.0, 3.0]);
    }

    #[test]
    fn slerp_halfway_and_held_at_the_ends() {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let track = Track {
            times: vec![1.0, 3.0],
            values: vec![vec![[1.0, 0.0, 0.0, 0.0]], vec![[h, h, 0.0, 0.0]]],
        };
        let mid = sample_rotations(&track, 2.0)[0];
        let (c, s) = (22.5f64.to_radians().cos(), 22.5f64.to_radians().sin());
        assert!((mid[0] - c).abs() < 1e-14 && (mid[1] - s).abs() < 1e-14);
        assert_eq!(sample_rotations(&track, -5.0)[0], [1.0, 0.0, 0.0, 0.0]);
        assert_eq!(sample_rotations(&track, 50.0)[0], [h, h, 0.0, 0.0]);
        // The opposite sign of the same rotation takes the short way.
        let neg = gf_slerp(0.5, [1.0, 0.0, 0.0, 0.0], [-h, -h, 0.0, 0.0]);
        assert!((neg[0] - c).abs() < 1e-14 && (neg[1] - s).abs() < 1e-14);
    }

    #[test]
    fn child_follows_parent_rotation() {
        let mut s = two_joints();
        let h = std::f64::consts::FRAC_1_SQRT_2;
        s.animation = Some(SkelAnimation {
            prim: "/S/Anim".into(),
            joints: vec![0],
            translations: Track {
                times: vec![],
                values: vec![vec![[0.0; 3]]],
            },
            rotations: Track {
                times: vec![],
                values: vec![vec![[h, h, 0.0, 0.0]]],
            },
            scales: None,
        });
        let x = skel_transforms(&s, 0.0).unwrap();
        // Joint B sits at z = 2 in rest; rotating A by 90 degrees about x puts it at y = -2.
        let p = nalgebra::RowVector4::new(0.0, 0.0, 0.0, 1.0) * x[1];
        assert!(p[0].abs() < 1e-12 && (p[1] + 2.0).abs() < 1e-12 && p[2].abs() < 1e-12);
    }

    #[test]
    fn singular_bind_is_an_error_naming_the_joint() {
        let mut s = two_joints();
        s.joints[1].bind = [[0.0; 4]; 4];
        let e = skinning_transforms(&s, 0.0).unwrap_err().to_string();
        assert!(e.contains("'A/B'") && e.contains("'/S'"), "{e}");
    }
}
