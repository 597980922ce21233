//! A `Stage` as cgnodes' `Scene` and `Camera`: meshes with a material of their mean display
//! colour, point clouds as octahedra (one per point, of the point's width) whose colours come
//! from a palette texture, UsdLux lights as cgnodes lights, and the camera: the stage's, else
//! `default_camera`'s framing of the geometry.

use super::model::{
    axis, translation, LightKind, Stage, StageCamera, StageLight, StageMesh, StagePoints, UpAxis,
};
use crate::BoxedError;
use cgnodes_api::types::vec3::{cross, sub, unit as norm};
use cgnodes_api::types::{
    Attribute, Camera, Domain, Image, Light, Material, Mesh, Scene, SceneObject,
};
use cgnodes_formats::usda::transform::Mat4;
use cgnodes_geometry::octahedron;
use std::path::PathBuf;
use std::sync::Arc;

/// Vertical field of view of the default framing, degrees.
pub const DEFAULT_FOV_DEG: f64 = 40.0;
/// Azimuth of the default view about the up axis, degrees (from the front, towards +x).
pub const DEFAULT_AZIMUTH_DEG: f64 = 30.0;
/// Elevation of the default view above the horizontal plane, degrees.
pub const DEFAULT_ELEVATION_DEG: f64 = 25.0;

/// The default framing of the box `lo..hi` (documented in docs/framework3d.md): looking at
/// the box centre from 30 degrees to the right of the front and 25 degrees above the
/// horizontal (front is -y when Z is up, +z when Y is up), with a vertical field of view of
/// 40 degrees, from the distance at which the bounding sphere of the box (radius half the
/// diagonal) fills the image height with 10 % to spare.
pub fn default_camera(lo: [f64; 3], hi: [f64; 3], up: UpAxis, width: u32, height: u32) -> Camera {
    let c = [
        0.5 * (lo[0] + hi[0]),
        0.5 * (lo[1] + hi[1]),
        0.5 * (lo[2] + hi[2]),
    ];
    let d2: f64 = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum();
    let r = (0.5 * d2.sqrt()).max(1e-3);
    let (az, el) = (
        DEFAULT_AZIMUTH_DEG.to_radians(),
        DEFAULT_ELEVATION_DEG.to_radians(),
    );
    let dir = match up {
        UpAxis::Z => [az.sin() * el.cos(), -az.cos() * el.cos(), el.sin()],
        UpAxis::Y => [az.sin() * el.cos(), el.sin(), az.cos() * el.cos()],
    };
    let dist = 1.1 * r / (0.5 * DEFAULT_FOV_DEG.to_radians()).sin();
    Camera {
        eye: [
            c[0] + dist * dir[0],
            c[1] + dist * dir[1],
            c[2] + dist * dir[2],
        ],
        target: c,
        up: up.vector(),
        fov_deg: DEFAULT_FOV_DEG,
        width,
        height,
        near: 0.01 * dist,
        far: 10.0 * (dist + r),
        ..Default::default()
    }
}

/// A `Camera` as a stage camera prim (local -Z looks at the target, +Y is up).
pub fn camera_prim(cam: &Camera, path: &str) -> StageCamera {
    let f = norm(sub(cam.target, cam.eye));
    let r = norm(cross(f, cam.up));
    let u = cross(r, f);
    let mut m = Mat4::identity();
    for k in 0..3 {
        m[(0, k)] = r[k];
        m[(1, k)] = u[k];
        m[(2, k)] = -f[k];
        m[(3, k)] = cam.eye[k];
    }
    StageCamera {
        path: path.to_string(),
        transform: m,
        fov_deg: cam.vertical_fov().to_degrees(),
        clipping: (cam.near, cam.far),
    }
}

/// A stage camera as a `Camera` of `width` x `height` pixels.
pub fn camera_of(c: &StageCamera, width: u32, height: u32) -> Camera {
    let eye = translation(&c.transform);
    let back = axis(&c.transform, 2);
    let (near, far) =
        if c.clipping.0 > 0.0 && c.clipping.1 > c.clipping.0 && c.clipping.1.is_finite() {
            c.clipping
        } else {
            (0.01, 1000.0)
        };
    Camera {
        eye,
        target: [eye[0] - back[0], eye[1] - back[1], eye[2] - back[2]],
        up: axis(&c.transform, 1),
        fov_deg: c.fov_deg,
        width,
        height,
        near,
        far,
        ..Default::default()
    }
}

/// Point clouds as octahedra: point `i` becomes an octahedron of half-diagonal `width_i / 2`
/// around it, all six vertices with the texture coordinate of texel `i` of a palette image
/// holding the point colours (so one material colours every particle; the rasterizer samples
/// a texel centre exactly). Returns the mesh and its material.
pub fn splat_points(p: &StagePoints) -> (Mesh, Material) {
    let n = p.points.len();
    let w = (n as f64).sqrt().ceil().max(1.0) as u32;
    let h = (n as u32).div_ceil(w).max(1);
    let mut pixels = vec![[0.8f32, 0.8, 0.8, 1.0]; (w * h) as usize];
    let mut positions = Vec::with_capacity(6 * n);
    let mut uvs = Vec::with_capacity(6 * n);
    let mut indices = Vec::with_capacity(24 * n);
    for (i, q) in p.points.iter().enumerate() {
        let r = 0.5
            * p.widths
                .get(i)
                .or(p.widths.first())
                .copied()
                .unwrap_or(0.05);
        let (tx, ty) = (i as u32 % w, i as u32 / w);
        if let Some(c) = &p.colors {
            let c = c.get(i).or(c.first()).copied().unwrap_or([0.8; 3]);
            pixels[(ty * w + tx) as usize] = [c[0] as f32, c[1] as f32, c[2] as f32, 1.0];
        }
        let uv = [
            (tx as f64 + 0.5) / w as f64,
            1.0 - (ty as f64 + 0.5) / h as f64,
        ];
        let base = positions.len() as u32;
        positions.extend(octahedron::positions(*q, r));
        uvs.extend([uv; 6]);
        for f in octahedron::FACES {
            indices.extend(f.iter().map(|k| base + k));
        }
    }
    let counts = vec![3u32; 8 * n];
    let mut mesh = Mesh::new(positions, counts, indices).unwrap_or_default();
    mesh.uvs = Some(Attribute {
        domain: Domain::Vertex,
        values: uvs,
    });
    let material = Material {
        name: format!("{}_points", p.path.trim_start_matches('/')),
        base_color: [1.0; 3],
        base_color_texture: Some(Arc::new(Image {
            width: w,
            height: h,
            pixels,
        })),
        ..Default::default()
    };
    (mesh, material)
}

/// Why a dome light's texture file could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum TextureError {
    /// The file exists but could not be read.
    #[error("{}: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The file's bytes are not an image the decoder reads.
    #[error("{}: {source}", path.display())]
    Decode { path: PathBuf, source: BoxedError },
}

/// Why a stage could not become a scene (`stage_to_scene`).
#[derive(Debug, thiserror::Error)]
pub enum StageSceneError {
    /// A dome light's texture could not be loaded.
    #[error(transparent)]
    Texture(#[from] TextureError),
    /// The stage's camera, or the default framing, is not a valid camera.
    #[error("camera: {0}")]
    Camera(BoxedError),
    /// A mesh could not be turned from Z-up to Y-up.
    #[error("{0}")]
    YUp(BoxedError),
}

/// Loads a dome light's texture by file name: `Ok(None)` when no file is found.
pub type ImageLoader<'a> = dyn FnMut(&str) -> Result<Option<Arc<Image>>, TextureError> + 'a;

/// Turns a stage into a scene and a camera of `width` x `height` pixels. `load_image`
/// loads a dome light's texture file (`Ok(None)`: not found, the dome keeps its constant
/// colour); what is approximated is pushed to `warnings` (rect lights become point lights of
/// the same power at their centre; a dome light's turn is kept about the up axis only).
pub fn stage_to_scene(
    stage: &Stage,
    width: u32,
    height: u32,
    load_image: &mut ImageLoader<'_>,
    warnings: &mut Vec<String>,
) -> Result<(Scene, Camera), StageSceneError> {
    let mut scene = Scene::default();
    scene.objects.extend(stage.meshes.iter().map(mesh_object));
    for p in &stage.points {
        if p.points.is_empty() {
            continue;
        }
        let (mesh, mat) = splat_points(p);
        scene.objects.push(SceneObject {
            mesh: Arc::new(mesh),
            material: Some(Arc::new(mat)),
        });
    }
    for l in &stage.lights {
        let light = scene_light(l, stage.up_axis, load_image, warnings)?;
        scene.lights.push(light);
    }
    let camera = match &stage.camera {
        Some(c) => camera_of(c, width, height),
        None => {
            let (lo, hi) = stage.bounds().unwrap_or(([-1.0; 3], [1.0; 3]));
            default_camera(lo, hi, stage.up_axis, width, height)
        }
    };
    camera
        .check()
        .map_err(|e| StageSceneError::Camera(e.into()))?;
    let mut camera = camera;
    if stage.up_axis == UpAxis::Z {
        y_up(&mut scene, &mut camera).map_err(StageSceneError::YUp)?;
    }
    scene.camera = Some(camera.clone());
    Ok((scene, camera))
}

/// A stage mesh as a scene object, with a material of its mean display colour when it has
/// display colours.
fn mesh_object(m: &StageMesh) -> SceneObject {
    let material = m
        .mesh
        .colors
        .as_ref()
        .filter(|c| !c.values.is_empty())
        .map(|c| {
            let mut s = [0.0; 3];
            for v in &c.values {
                for k in 0..3 {
                    s[k] += v[k];
                }
            }
            let n = c.values.len() as f64;
            Arc::new(Material {
                name: m.path.trim_start_matches('/').to_string(),
                base_color: [s[0] / n, s[1] / n, s[2] / n],
                ..Default::default()
            })
        });
    SceneObject {
        mesh: Arc::new(m.mesh.clone()),
        material,
    }
}

/// A UsdLux light as a cgnodes light: sphere lights as point lights, distant lights along
/// their -z axis, rect lights as point lights of the same power (with a warning), dome
/// lights as environment lights (`dome_light`).
fn scene_light(
    l: &StageLight,
    up: UpAxis,
    load_image: &mut ImageLoader<'_>,
    warnings: &mut Vec<String>,
) -> Result<Light, TextureError> {
    let pos = translation(&l.transform);
    let z = axis(&l.transform, 2);
    Ok(match &l.kind {
        LightKind::Sphere { .. } => Light::Point {
            position: pos,
            color: l.color,
            intensity: l.intensity,
        },
        LightKind::Distant { .. } => Light::Directional {
            direction: [-z[0], -z[1], -z[2]],
            color: l.color,
            intensity: l.intensity,
        },
        LightKind::Rect { width, height } => {
            warnings.push(format!(
                "{}: a rect light is drawn as a point light at its centre",
                l.path
            ));
            Light::Point {
                position: pos,
                color: l.color,
                intensity: l.intensity * width * height,
            }
        }
        LightKind::Dome { file } => dome_light(l, file, up, load_image, warnings)?,
    })
}

/// A dome light as an environment light: its texture `file` loaded through `load_image`
/// (a warning when not found: the dome keeps its constant colour) and its turn about the
/// `up` axis, from where the local x axis went.
fn dome_light(
    l: &StageLight,
    file: &str,
    up: UpAxis,
    load_image: &mut ImageLoader<'_>,
    warnings: &mut Vec<String>,
) -> Result<Light, TextureError> {
    let image = if file.is_empty() {
        None
    } else {
        let img = load_image(file)?;
        if img.is_none() {
            warnings.push(format!(
                "{}: texture '{file}' not found (next to the stage, in the project or --assets folders); the dome light keeps its constant colour",
                l.path
            ));
        }
        img
    };
    let x = axis(&l.transform, 0);
    let rot = match up {
        UpAxis::Y => (-x[2]).atan2(x[0]),
        UpAxis::Z => x[1].atan2(x[0]),
    };
    Ok(Light::Environment {
        image,
        color: l.color,
        intensity: l.intensity,
        rotation_deg: rot.to_degrees(),
    })
}

/// Turns a Z-up stage's scene and camera into cgnodes' Y-up convention, (x, y, z) ->
/// (x, z, -y) (a rotation by -90 degrees about x): the environment light's equirectangular
/// image has its poles on +-y (`nodes/trace/environment.rs`), so a Framework3D dome light is
/// seen with its horizon level. Images are unchanged; only world coordinates turn (the
/// dome's turn about the up axis keeps its angle).
fn y_up(scene: &mut Scene, camera: &mut Camera) -> Result<(), BoxedError> {
    let r = |p: [f64; 3]| [p[0], p[2], -p[1]];
    let m = nalgebra::Matrix4::new(
        1.0, 0.0, 0.0, 0.0, //
        0.0, 0.0, 1.0, 0.0, //
        0.0, -1.0, 0.0, 0.0, //
        0.0, 0.0, 0.0, 1.0,
    );
    for o in &mut scene.objects {
        o.mesh = Arc::new(cgnodes_geometry::transform::transform_mesh(&o.mesh, &m)?);
    }
    for l in &mut scene.lights {
        match l {
            Light::Point { position, .. } => *position = r(*position),
            Light::Directional { direction, .. } => *direction = r(*direction),
            Light::Environment { .. } => {}
        }
    }
    camera.eye = r(camera.eye);
    camera.target = r(camera.target);
    camera.up = r(camera.up);
    Ok(())
}
