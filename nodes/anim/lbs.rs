//! Linear blend skinning (study book §2.9.2.2; Magnenat-Thalmann et al. 1988): each vertex
//! moves by the weighted sum of its joints' transforms, `p' = Σ_j w_j (p G S_j) W` in USD's
//! row-vector form, with `G` the geometry bind transform, `S_j = bind_j⁻¹ skel_j` the joint's
//! skinning transform and `W` the skeleton's placement in the output space
//! (`UsdSkelSkinPointsLBS`). Normals are blended the same way through the inverse transposes
//! of the linear parts (`UsdSkelSkinNormalsLBS`) and renormalized. Also the shared input
//! checks of both skinning methods (`check_influences`, `normalize_weights`).

use cgnodes_formats::usda::transform::Mat4;
use nalgebra::Matrix3;
use rayon::prelude::*;

/// Why skinning cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SkinError {
    /// A joint index beyond the skeleton.
    #[error("vertex {vertex} refers to joint {index}, but the skeleton has {count} joints")]
    JointOutOfRange {
        vertex: usize,
        index: u32,
        count: usize,
    },
    /// Indices and weights of different lengths, or not `influences` per vertex.
    #[error("{indices} joint indices and {weights} weights for {vertices} vertices with {influences} influences each")]
    Lengths {
        indices: usize,
        weights: usize,
        vertices: usize,
        influences: usize,
    },
    /// A vertex whose weights add up to zero (or are not finite).
    #[error("the weights of vertex {0} add up to {1}, which cannot be normalized")]
    ZeroWeights(usize, f64),
    /// A transform whose linear part has no inverse (for normals).
    #[error("the transform of joint {0} is singular, so normals cannot be skinned")]
    Singular(usize),
}

/// Per-vertex joint influences: `count` (joint, weight) pairs per vertex, flattened.
#[derive(Clone, Copy, Debug)]
pub struct Influences<'a> {
    /// Influences per vertex.
    pub count: usize,
    /// Joint indices, `count` per vertex.
    pub indices: &'a [u32],
    /// Weights, `count` per vertex.
    pub weights: &'a [f64],
}

/// Checks lengths and joint indices against `num_vertices` and `num_joints`.
pub fn check_influences(
    inf: &Influences,
    num_vertices: usize,
    num_joints: usize,
) -> Result<(), SkinError> {
    let want = num_vertices.checked_mul(inf.count);
    if inf.count == 0 || want != Some(inf.indices.len()) || inf.indices.len() != inf.weights.len() {
        return Err(SkinError::Lengths {
            indices: inf.indices.len(),
            weights: inf.weights.len(),
            vertices: num_vertices,
            influences: inf.count,
        });
    }
    if let Some(k) = inf.indices.iter().position(|&j| j as usize >= num_joints) {
        return Err(SkinError::JointOutOfRange {
            vertex: k / inf.count,
            index: inf.indices[k],
            count: num_joints,
        });
    }
    Ok(())
}

/// Weights scaled so that each vertex's add up to 1, and how many vertices needed it (a sum
/// off by more than 1e-6). A zero or non-finite sum is an error.
pub fn normalize_weights(count: usize, weights: &[f64]) -> Result<(Vec<f64>, usize), SkinError> {
    let mut out = weights.to_vec();
    let mut changed = 0;
    for (v, w) in out.chunks_mut(count.max(1)).enumerate() {
        let s: f64 = w.iter().sum();
        if !s.is_finite() || s.abs() < 1e-12 {
            return Err(SkinError::ZeroWeights(v, s));
        }
        if (s - 1.0).abs() > 1e-6 {
            changed += 1;
            w.iter_mut().for_each(|x| *x /= s);
        }
    }
    Ok((out, changed))
}

/// An affine row-vector transform as its four rows' first three columns.
type Affine = [[f64; 3]; 4];

fn affine(m: &Mat4) -> Affine {
    std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]))
}

#[inline(always)]
fn apply(m: &Affine, p: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|c| p[0] * m[0][c] + p[1] * m[1][c] + p[2] * m[2][c] + m[3][c])
}

/// The full per-joint matrices of LBS, `G S_j W`.
pub fn joint_matrices(geom_bind: &Mat4, skinning: &[Mat4], post: &Mat4) -> Vec<Mat4> {
    skinning.iter().map(|s| geom_bind * s * post).collect()
}

/// Skins `points` with the per-joint matrices `xf` (`joint_matrices`): `p' = Σ w_j p xf_j`.
/// Influences must have passed `check_influences` against `xf.len()`.
pub fn lbs_points(points: &[[f64; 3]], inf: &Influences, xf: &[Mat4]) -> Vec<[f64; 3]> {
    let aff: Vec<Affine> = xf.iter().map(affine).collect();
    let k = inf.count;
    let mut out = vec![[0.0; 3]; points.len()];
    out.par_iter_mut()
        .with_min_len(2048)
        .enumerate()
        .for_each(|(v, o)| {
            let p = points[v];
            let mut acc = [0.0; 3];
            for i in v * k..v * k + k {
                let w = inf.weights[i];
                if w != 0.0 {
                    let q = apply(&aff[inf.indices[i] as usize], p);
                    for c in 0..3 {
                        acc[c] += w * q[c];
                    }
                }
            }
            *o = acc;
        });
    out
}

/// Skins normals: `n' = normalize(Σ w_j n (A_j⁻¹)ᵀ)` with `A_j` the linear part of `xf_j`;
/// `vertex_of[i]` is the vertex whose influences normal `i` takes (`None`: normal `i` is
/// vertex `i`'s).
pub fn lbs_normals(
    normals: &[[f64; 3]],
    vertex_of: Option<&[u32]>,
    inf: &Influences,
    xf: &[Mat4],
) -> Result<Vec<[f64; 3]>, SkinError> {
    let inv_t = xf
        .iter()
        .enumerate()
        .map(|(j, m)| {
            let a: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
            a.try_inverse()
                .map(|i| i.transpose())
                .ok_or(SkinError::Singular(j))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let k = inf.count;
    let mut out = vec![[0.0; 3]; normals.len()];
    out.par_iter_mut()
        .with_min_len(2048)
        .enumerate()
        .for_each(|(i, o)| {
            let v = vertex_of.map_or(i, |m| m[i] as usize);
            let n = nalgebra::RowVector3::from(normals[i]);
            let mut acc = nalgebra::RowVector3::zeros();
            for e in v * k..v * k + k {
                let w = inf.weights[e];
                if w != 0.0 {
                    acc += (n * inv_t[inf.indices[e] as usize]) * w;
                }
            }
            let len = acc.norm();
            *o = if len > 0.0 {
                [acc[0] / len, acc[1] / len, acc[2] / len]
            } else {
                normals[i]
            };
        });
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_and_half_between_two_translations() {
        let mut a = Mat4::identity();
        a[(3, 0)] = 2.0;
        let mut b = Mat4::identity();
        b[(3, 1)] = 4.0;
        let inf = Influences {
            count: 2,
            indices: &[0, 1],
            weights: &[0.5, 0.5],
        };
        let p = lbs_points(&[[1.0, 1.0, 1.0]], &inf, &[a, b]);
        assert_eq!(p[0], [2.0, 3.0, 1.0]);
    }

    #[test]
    fn bad_indices_and_lengths_are_errors() {
        let inf = Influences {
            count: 2,
            indices: &[0, 3],
            weights: &[0.5, 0.5],
        };
        assert!(matches!(
            check_influences(&inf, 1, 2),
            Err(SkinError::JointOutOfRange {
                vertex: 0,
                index: 3,
                count: 2
            })
        ));
        let inf = Influences {
            count: 2,
            indices: &[0, 1],
            weights: &[1.0],
        };
        assert!(matches!(
            check_influences(&inf, 1, 2),
            Err(SkinError::Lengths { .. })
        ));
    }

    #[test]
    fn weights_are_normalized_and_counted() {
        let (w, n) = normalize_weights(2, &[1.0, 1.0, 0.25, 0.75]).unwrap();
        assert_eq!((w, n), (vec![0.5, 0.5, 0.25, 0.75], 1));
        assert!(matches!(
            normalize_weights(2, &[0.0, 0.0]),
            Err(SkinError::ZeroWeights(0, _))
        ));
    }

    #[test]
    fn normals_follow_a_rotation_and_ignore_translation() {
        let mut r = Mat4::identity();
        // 90 degrees about z in row-vector form: x -> y.
        r[(0, 0)] = 0.0;
        r[(0, 1)] = 1.0;
        r[(1, 0)] = -1.0;
        r[(1, 1)] = 0.0;
        r[(3, 2)] = 5.0;
        let inf = Influences {
            count: 1,
            indices: &[0],
            weights: &[1.0],
        };
        let n = lbs_normals(&[[1.0, 0.0, 0.0]], None, &inf, &[r]).unwrap();
        assert!((n[0][1] - 1.0).abs() < 1e-15 && n[0][0].abs() < 1e-15);
    }
}
