use super::{Image, Mesh};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Which image axis the field of view spans.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum FovAxis {
    /// The vertical axis.
    Vertical,
    /// Whichever of width and height is smaller (Mitsuba's `fov_axis = smaller`).
    Smaller,
}

/// A pinhole camera looking from `eye` at `target`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Camera position.
    pub eye: [f64; 3],
    /// Point looked at.
    pub target: [f64; 3],
    /// Up direction.
    pub up: [f64; 3],
    /// Field of view in degrees along `fov_axis`.
    pub fov_deg: f64,
    /// Axis the field of view spans.
    pub fov_axis: FovAxis,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Near clipping distance.
    pub near: f64,
    /// Far clipping distance.
    pub far: f64,
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            eye: [0.0, 0.0, 3.0],
            target: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            fov_deg: 45.0,
            fov_axis: FovAxis::Vertical,
            width: 512,
            height: 512,
            near: 0.01,
            far: 1000.0,
        }
    }
}

impl Camera {
    /// The vertical field of view in radians, whatever axis `fov_deg` was given on.
    pub fn vertical_fov(&self) -> f64 {
        let f = self.fov_deg.to_radians();
        match self.fov_axis {
            FovAxis::Vertical => f,
            FovAxis::Smaller if self.height <= self.width => f,
            FovAxis::Smaller => {
                let aspect = self.height as f64 / self.width as f64;
                2.0 * ((f * 0.5).tan() * aspect).atan()
            }
        }
    }
}

/// A light source.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Light {
    /// A point light radiating `color * intensity` (W/sr per channel) in every direction.
    Point {
        position: [f64; 3],
        color: [f64; 3],
        intensity: f64,
    },
    /// A distant light travelling along `direction`, with irradiance `color * intensity`.
    Directional {
        direction: [f64; 3],
        color: [f64; 3],
        intensity: f64,
    },
}

/// How a surface scatters light (used by the ray and path tracers; the rasterizer uses
/// the Blinn-Phong parameters of `Material`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum MaterialKind {
    /// Lambertian diffuse.
    Diffuse,
    /// Perfect mirror.
    Mirror,
    /// Smooth dielectric with index of refraction `ior`.
    Dielectric { ior: f64 },
    /// GGX microfacet conductor.
    Conductor { roughness: f64 },
}

/// A surface's appearance.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Name (used for MTL files).
    pub name: String,
    /// Scattering model.
    pub kind: MaterialKind,
    /// Linear base colour (diffuse albedo).
    pub base_color: [f64; 3],
    /// Base colour texture, sampled through the mesh's UVs (multiplies `base_color`).
    pub base_color_texture: Option<Arc<Image>>,
    /// Metallic, 0 to 1.
    pub metallic: f64,
    /// Roughness, 0 to 1.
    pub roughness: f64,
    /// Tangent-space normal map.
    pub normal_map: Option<Arc<Image>>,
    /// Emitted radiance (linear RGB).
    pub emission: [f64; 3],
    /// Whether the emission leaves both sides of the surface.
    pub two_sided_emission: bool,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: "default".into(),
            kind: MaterialKind::Diffuse,
            base_color: [0.8, 0.8, 0.8],
            base_color_texture: None,
            metallic: 0.0,
            roughness: 0.5,
            normal_map: None,
            emission: [0.0; 3],
            two_sided_emission: false,
        }
    }
}

/// A mesh placed in a scene with its material.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SceneObject {
    /// The geometry (world space).
    pub mesh: Arc<Mesh>,
    /// Its material; `None` uses the mesh's own material or the default.
    pub material: Option<Arc<Material>>,
}

/// What a renderer draws: objects, lights and a camera.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Scene {
    /// Meshes with materials.
    pub objects: Vec<SceneObject>,
    /// Light sources (emissive materials are lights too, for the path tracer).
    pub lights: Vec<Light>,
    /// The camera, if the scene has one.
    pub camera: Option<Camera>,
}

impl Scene {
    /// A scene holding just one mesh (the implicit Mesh to Scene conversion).
    pub fn from_mesh(mesh: Arc<Mesh>) -> Scene {
        Scene {
            objects: vec![SceneObject {
                mesh,
                material: None,
            }],
            ..Default::default()
        }
    }
}
