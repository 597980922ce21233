//! The stage as plain data: world-space meshes and point clouds, UsdLux lights with their
//! world transforms, and an optional camera. Paths are absolute USD prim paths.

use cgnodes_api::types::Mesh;
use cgnodes_formats::usda::transform::Mat4;

/// The stage's up axis (`upAxis` layer metadata): Framework3D's stages are Z up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UpAxis {
    /// +Y up (USD's default when a layer does not say).
    Y,
    /// +Z up (Framework3D, Blender exports).
    Z,
}

impl UpAxis {
    /// The up direction as a vector.
    pub fn vector(self) -> [f64; 3] {
        match self {
            UpAxis::Y => [0.0, 1.0, 0.0],
            UpAxis::Z => [0.0, 0.0, 1.0],
        }
    }
}

/// A mesh prim, its geometry in world space (transforms applied).
#[derive(Clone, Debug)]
pub struct StageMesh {
    /// Prim path, e.g. `/geometry2`.
    pub path: String,
    /// Geometry with normals, UVs and display colours when the prim has them.
    pub mesh: Mesh,
}

/// A `Points` prim (UsdGeomPoints), such as SPH particles, in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct StagePoints {
    /// Prim path.
    pub path: String,
    /// Positions.
    pub points: Vec<[f64; 3]>,
    /// Diameters, one per point or one for all.
    pub widths: Vec<f64>,
    /// Display colours, one per point or one for all; `None` when the prim has none.
    pub colors: Option<Vec<[f64; 3]>>,
}

/// Which UsdLux light.
#[derive(Clone, Debug, PartialEq)]
pub enum LightKind {
    /// `SphereLight` (Framework3D's point light) of radius `radius`.
    Sphere {
        /// `inputs:radius`.
        radius: f64,
    },
    /// `DistantLight`, shining along its local -Z; `angle` is its angular diameter (degrees).
    Distant {
        /// `inputs:angle`.
        angle: f64,
    },
    /// `DomeLight`: light from every direction, from an equirectangular image `file` (as
    /// written, resolved when the stage is turned into a scene; empty for none).
    Dome {
        /// `inputs:texture:file`.
        file: String,
    },
    /// `RectLight` of `width` x `height` in its local XY plane, shining along local -Z.
    Rect {
        /// `inputs:width`.
        width: f64,
        /// `inputs:height`.
        height: f64,
    },
}

/// A UsdLux light.
#[derive(Clone, Debug, PartialEq)]
pub struct StageLight {
    /// Prim path, e.g. `/Reference/XFormDomeLight/DomeLight` as Framework3D writes it.
    pub path: String,
    /// Kind and its own parameters.
    pub kind: LightKind,
    /// `inputs:color` (linear RGB).
    pub color: [f64; 3],
    /// `inputs:intensity` (USD's default 1).
    pub intensity: f64,
    /// World transform (USD row-vector convention: row 3 is the position).
    pub transform: Mat4,
}

/// A `Camera` prim: a pinhole looking along its local -Z with +Y up.
#[derive(Clone, Debug, PartialEq)]
pub struct StageCamera {
    /// Prim path.
    pub path: String,
    /// World transform (row-vector convention).
    pub transform: Mat4,
    /// Vertical field of view in degrees (`2 atan(verticalAperture / (2 focalLength))`).
    pub fov_deg: f64,
    /// `clippingRange` (near, far).
    pub clipping: (f64, f64),
}

/// A whole stage.
#[derive(Clone, Debug)]
pub struct Stage {
    /// `upAxis`.
    pub up_axis: UpAxis,
    /// Mesh prims.
    pub meshes: Vec<StageMesh>,
    /// Points prims.
    pub points: Vec<StagePoints>,
    /// Lights.
    pub lights: Vec<StageLight>,
    /// The camera (the first `Camera` prim).
    pub camera: Option<StageCamera>,
}

impl Default for Stage {
    fn default() -> Self {
        Stage {
            up_axis: UpAxis::Z,
            meshes: Vec::new(),
            points: Vec::new(),
            lights: Vec::new(),
            camera: None,
        }
    }
}

impl Stage {
    /// Adds everything of `other` (its up axis is ignored: a project's layers share one).
    pub fn merge(&mut self, other: Stage) {
        self.meshes.extend(other.meshes);
        self.points.extend(other.points);
        self.lights.extend(other.lights);
        if self.camera.is_none() {
            self.camera = other.camera;
        }
    }

    /// Moves every prim under `prefix` (Framework3D's `comp_merge_to_global` references a
    /// layer under `/Reference/<Path>`).
    pub fn reroot(&mut self, prefix: &str) {
        let p = prefix.trim_end_matches('/');
        for m in &mut self.meshes {
            m.path = format!("{p}{}", m.path);
        }
        for m in &mut self.points {
            m.path = format!("{p}{}", m.path);
        }
        for l in &mut self.lights {
            l.path = format!("{p}{}", l.path);
        }
        if let Some(c) = &mut self.camera {
            c.path = format!("{p}{}", c.path);
        }
    }

    /// The bounds of the geometry (meshes and points, widths included); `None` when there is
    /// none.
    pub fn bounds(&self) -> Option<([f64; 3], [f64; 3])> {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        let mut add = |p: &[f64; 3], r: f64| {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k] - r);
                hi[k] = hi[k].max(p[k] + r);
            }
        };
        for m in &self.meshes {
            for p in &m.mesh.positions {
                add(p, 0.0);
            }
        }
        for s in &self.points {
            for (i, p) in s.points.iter().enumerate() {
                let w = s.widths.get(i).or(s.widths.first()).copied().unwrap_or(0.0);
                add(p, 0.5 * w);
            }
        }
        (lo[0] <= hi[0]).then_some((lo, hi))
    }
}

/// The translation of a row-vector transform (its row 3).
pub fn translation(m: &Mat4) -> [f64; 3] {
    [m[(3, 0)], m[(3, 1)], m[(3, 2)]]
}

/// The image of local axis `k` (0 x, 1 y, 2 z) under a row-vector transform, normalized.
pub fn axis(m: &Mat4, k: usize) -> [f64; 3] {
    let v = [m[(k, 0)], m[(k, 1)], m[(k, 2)]];
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if l > 0.0 {
        [v[0] / l, v[1] / l, v[2] / l]
    } else {
        v
    }
}
