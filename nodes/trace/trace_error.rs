//! The tracers' errors: why a tracer could not start (`TraceError`, by the socket it
//! concerns) and why a scene cannot be traced (`SceneError`).

use super::camera::CameraError;
use cgnodes_geometry::scene_geometry::SceneGeometryError;

/// Why a tracer could not start, by the socket it concerns.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TraceError {
    /// No camera is linked and the scene has none.
    #[error("no camera: connect one to `camera` or give the scene one")]
    NoCamera,
    /// The camera cannot be used (non-finite, degenerate, out-of-range size or field of view).
    #[error("{0}")]
    Camera(#[from] CameraError),
    /// The scene cannot be rendered (non-finite vertices, bad indices).
    #[error("{0}")]
    Scene(#[from] SceneError),
}

/// Why a scene cannot be traced.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// A NaN or infinite vertex.
    #[error("object {object}: vertex {vertex} is not finite")]
    NonFiniteVertex {
        /// The object's index in the scene.
        object: usize,
        /// The vertex's index in its mesh.
        vertex: usize,
    },
    /// A face under 3 corners or with an index past the vertices.
    #[error("object {object}: a face has a bad vertex index")]
    BadFace {
        /// The object's index in the scene.
        object: usize,
    },
    /// A crease angle outside 0..=180 degrees.
    #[error("crease angle {0} must be in 0..=180 degrees")]
    Crease(f64),
    /// The scene could not be flattened.
    #[error("{0}")]
    Geometry(#[from] SceneGeometryError),
    /// A point light with a NaN or infinite parameter.
    #[error("a point light has a non-finite parameter")]
    PointLight,
    /// A directional light with a non-finite or zero direction (or non-finite colour).
    #[error("a directional light needs a finite non-zero direction")]
    DirectionalLight,
}

impl TraceError {
    /// The input socket the error is about: `camera` or `scene`.
    pub fn socket(&self) -> &'static str {
        match self {
            TraceError::NoCamera | TraceError::Camera(_) => "camera",
            TraceError::Scene(_) => "scene",
        }
    }
}
