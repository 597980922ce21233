//! Socket types and the values that travel along links.
//!
//! Heavy values (meshes, images, ...) are held in `Arc`s so that passing them between nodes
//! never copies; a node that wants to change one calls `Arc::make_mut` (clone on write).

mod image_ops;
mod mesh;
mod misc;
mod model;
mod scene;
mod skeleton;
mod topology;
mod value;

pub mod vec3;

pub use image_ops::TRANSPARENT;
pub use mesh::{Attribute, AttributeData, Domain, Mesh, MeshError};
pub use misc::{Curve, Image, Points, Table};
pub use model::{DenseLayer, Model};
pub use scene::{Camera, FovAxis, Light, LookAt, Material, MaterialKind, Scene, SceneObject};
pub use skeleton::{
    Joint, RowMatrix, SkelAnimation, Skeleton, SkinBinding, Track, IDENTITY as IDENTITY_MATRIX,
};
pub use topology::{grid_triangles, grid_triangles_with, NotADisk, Topology};
pub use value::{Color, FromValue, SocketType, Typed, Value};

/// The `Any` socket type marker (`b.add_input::<value_any::Any>("value")`).
pub mod value_any {
    pub use super::value::AnyValue as Any;
}
