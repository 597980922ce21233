//! Skeletons for skinning, laid out as UsdSkel lays them out: joints in an order where parents
//! come first, bind transforms in skeleton space, rest transforms relative to the parent, and
//! an optional animation (per-joint translation, rotation and scale tracks over USD time codes).
//!
//! Matrices use USD's row-vector convention (`p' = p * M`, translation in the last row) and are
//! stored row by row as the file writes them. The pose at a time and the skinning itself are in
//! `nodes::anim`; this is the plain data that travels on `skeleton` sockets.

use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// A 4x4 matrix in USD's row-vector convention, rows as written in a `.usda` file.
pub type RowMatrix = [[f64; 4]; 4];

/// The identity `RowMatrix`.
pub const IDENTITY: RowMatrix = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// A joint of a skeleton.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Joint {
    /// The joint's path token as in the Skeleton's `joints` (`Shoulder/Elbow`).
    pub path: String,
    /// Index of the parent joint (always smaller than this joint's), `None` for a root.
    pub parent: Option<usize>,
    /// World (skeleton space) transform of the joint at bind time (`bindTransforms`).
    pub bind: RowMatrix,
    /// Transform relative to the parent when not animated (`restTransforms`).
    pub rest: RowMatrix,
}

impl Joint {
    /// The last component of the path (`Elbow`).
    pub fn name(&self) -> &str {
        self.path.rsplit('/').next().unwrap_or(&self.path)
    }
}

/// Values of one animated quantity for every animated joint: constant (one sample, no
/// times) or sampled at increasing USD time codes (`timeSamples`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Track<T> {
    /// Sample times, increasing; empty for a constant value.
    pub times: Vec<f64>,
    /// One array (one entry per animated joint) per time, or one array when constant.
    pub values: Vec<Vec<T>>,
}

/// A `SkelAnimation`: local transforms of a subset of the skeleton's joints over time.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SkelAnimation {
    /// The prim path of the animation (named in errors).
    pub prim: String,
    /// For each animated entry, the index of the skeleton joint it drives.
    pub joints: Vec<usize>,
    /// Translations (linear interpolation between samples).
    pub translations: Track<[f64; 3]>,
    /// Rotations as quaternions `(real, i, j, k)` (slerp between samples, as USD's `GfSlerp`).
    pub rotations: Track<[f64; 4]>,
    /// Scales (linear interpolation); `None` when not authored (unit scale).
    pub scales: Option<Track<[f64; 3]>>,
}

/// A joint hierarchy for skinning, with its animation.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Skeleton {
    /// The prim path of the Skeleton (named in errors).
    pub prim: String,
    /// Joints, parents before children.
    pub joints: Vec<Joint>,
    /// The bound animation (`skel:animationSource`), if any.
    pub animation: Option<SkelAnimation>,
}

impl Skeleton {
    /// The index of the joint whose path is `path`.
    pub fn joint_index(&self, path: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.path == path)
    }
}

/// How a mesh is bound to a skeleton (UsdSkel's `SkelBindingAPI` on the mesh): a fixed number
/// of influences per vertex, each a joint index and a weight, and the geometry bind transform.
/// Shared through an `Arc` on the mesh so that passing a bound mesh around copies nothing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SkinBinding {
    /// The bound mesh prim (named in errors).
    pub prim: String,
    /// The skeleton the mesh is bound to (`skel:skeleton`).
    pub skeleton: Arc<Skeleton>,
    /// Influences per vertex (`elementSize` of the primvars).
    pub influences: usize,
    /// `influences` joint indices per vertex, into `skeleton.joints`.
    pub joint_indices: Vec<u32>,
    /// `influences` weights per vertex.
    pub joint_weights: Vec<f64>,
    /// `primvars:skel:geomBindTransform`, from the mesh's points to skeleton space at bind time,
    /// with the inverse of any transform the loader applied to the points folded in.
    pub geom_bind: RowMatrix,
    /// Skeleton space to the space the skinned points are returned in (the Skeleton prim's
    /// world transform when the loader applies transforms, else the identity).
    pub skel_to_world: RowMatrix,
}

impl SkinBinding {
    /// Number of vertices the binding covers.
    pub fn num_vertices(&self) -> usize {
        self.joint_indices.len() / self.influences.max(1)
    }
}
