//! A mesh's preview image: the rasterizer from a fixed three-quarter view with a head light,
//! a UV checkerboard when the mesh has UVs. Used by `mesh_sequence` (framing fixed from the
//! first frame so an animation does not jump) and by the run report's mesh thumbnails.

use super::raster::{self, Passes, RasterOptions};
use cgnodes_api::prelude::*;
use serde::{Deserialize, Serialize};

/// What the preview camera frames: a bounding sphere.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Framing {
    /// Centre of the mesh's bounding box.
    pub center: [f64; 3],
    /// Half the bounding box's diagonal (at least 1e-6).
    pub radius: f64,
}

impl Framing {
    /// The bounding sphere of `mesh`'s bounding box; `None` for a mesh without vertices or
    /// with non-finite positions.
    pub fn of(mesh: &Mesh) -> Option<Framing> {
        if mesh.positions.is_empty() {
            return None;
        }
        let (lo, hi) = mesh.bounds();
        if !lo.iter().chain(&hi).all(|v| v.is_finite()) {
            return None;
        }
        let center = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
        let d2: f64 = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum();
        Some(Framing {
            center,
            radius: (0.5 * d2.sqrt()).max(1e-6),
        })
    }
}

/// The direction from the framed centre to the eye: a three-quarter view from the front
/// right and above (+x, +y, +z with y up).
pub const VIEW_DIR: [f64; 3] = [0.6, 0.45, 0.75];

/// The preview camera of a `width` x `height` image: looks at the framing's centre along
/// `-VIEW_DIR`, 30 degrees vertical field of view, far enough that the bounding sphere fits.
pub fn preview_camera(f: &Framing, width: u32, height: u32) -> Camera {
    let n = VIEW_DIR.iter().map(|v| v * v).sum::<f64>().sqrt();
    let fov = 30f64;
    let aspect = width as f64 / height.max(1) as f64;
    // The sphere fits the narrower of the two half-angles.
    let half = (fov.to_radians() / 2.0).tan().atan();
    let half_h = (half.tan() * aspect.min(1.0)).atan();
    let dist = f.radius / half_h.sin() * 1.05;
    Camera {
        eye: [0, 1, 2].map(|k| f.center[k] + VIEW_DIR[k] / n * dist),
        target: f.center,
        up: [0.0, 1.0, 0.0],
        fov_deg: fov,
        fov_axis: FovAxis::Vertical,
        width,
        height,
        near: (dist - f.radius * 1.5).max(dist * 1e-3),
        far: dist + f.radius * 1.5,
    }
}

/// The preview of `mesh` at `width` x `height`, framed on the bounds of `framing_of` (a
/// sequence's first frame, so a moving mesh moves in the frame): the run report's mesh
/// thumbnails (`MeshHooks::preview`).
pub fn preview_framed_on(
    framing_of: &Mesh,
    mesh: &Arc<Mesh>,
    width: u32,
    height: u32,
) -> Result<Image, String> {
    // The string error is `MeshHooks::preview`'s (the API's hook type).
    let framing = Framing::of(framing_of).ok_or("no finite vertices")?;
    render_preview(mesh, Some(framing), width, height).map_err(|e| e.to_string())
}

/// Why a mesh preview cannot be drawn.
#[derive(Debug, thiserror::Error)]
pub enum PreviewError {
    /// The mesh has no vertex with finite coordinates to frame.
    #[error("the mesh has no (finite) vertices")]
    NoVertices,
    /// The rasterizer refused the preview scene.
    #[error(transparent)]
    Raster(#[from] raster::RasterError),
}

/// Renders `mesh` as a preview with `framing` (the mesh's own when `None`): light grey
/// background, a head light plus ambient, a checkerboard of 8 x 8 squares through the UVs
/// when the mesh has them, else a light blue-grey surface. Fails on a mesh with no
/// vertices or non-finite positions.
pub fn render_preview(
    mesh: &Arc<Mesh>,
    framing: Option<Framing>,
    width: u32,
    height: u32,
) -> Result<Image, PreviewError> {
    let f = match framing {
        Some(f) => f,
        None => Framing::of(mesh).ok_or(PreviewError::NoVertices)?,
    };
    let cam = preview_camera(&f, width, height);
    // The checkerboard is made once per process: previews run on every report.
    static CHECKER: std::sync::OnceLock<Arc<Image>> = std::sync::OnceLock::new();
    let material = if mesh.uvs.is_some() {
        Material {
            name: "preview_checker".into(),
            base_color: [1.0; 3],
            base_color_texture: Some(
                CHECKER
                    .get_or_init(|| Arc::new(cgnodes_geometry::checkerboard::checkerboard(256, 8)))
                    .clone(),
            ),
            ..Default::default()
        }
    } else {
        Material {
            name: "preview".into(),
            base_color: [0.55, 0.62, 0.75],
            ..Default::default()
        }
    };
    let n = VIEW_DIR.iter().map(|v| v * v).sum::<f64>().sqrt();
    // Light travels from above the camera's left towards the mesh.
    let dir = [
        -VIEW_DIR[0] / n + 0.3,
        -VIEW_DIR[1] / n - 0.4,
        -VIEW_DIR[2] / n,
    ];
    let scene = Scene {
        objects: vec![SceneObject {
            mesh: mesh.clone(),
            material: Some(Arc::new(material)),
        }],
        lights: vec![Light::Directional {
            direction: dir,
            color: [1.0; 3],
            intensity: 0.9,
        }],
        camera: None,
    };
    let opts = RasterOptions {
        shadows: false,
        ambient: 0.35,
        background: [0.85, 0.86, 0.88],
        passes: Passes::COLOR,
        mipmaps: false,
        ..Default::default()
    };
    Ok(raster::render(&scene, &cam, &opts)?.color)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(uv: bool) -> Arc<Mesh> {
        let mut m = Mesh::from_triangles(
            vec![
                [-1.0, -1.0, 0.0],
                [1.0, -1.0, 0.0],
                [1.0, 1.0, 0.0],
                [-1.0, 1.0, 0.0],
            ],
            &[[0, 1, 2], [0, 2, 3]],
        )
        .unwrap();
        if uv {
            m.uvs = Some(Attribute {
                domain: Domain::Vertex,
                values: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            });
        }
        Arc::new(m)
    }

    #[test]
    fn preview_shows_the_mesh_centred_and_the_checker_when_it_has_uvs() {
        let (w, h) = (64, 48);
        let bg = 0.85f32;
        let plain = render_preview(&quad(false), None, w, h).unwrap();
        let covered: Vec<(u32, u32)> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| (plain.get(x, y)[0] - bg).abs() > 0.02)
            .collect();
        // The quad covers a good part of the frame, around its centre, and stays inside it.
        assert!(covered.len() > (w * h / 8) as usize, "{}", covered.len());
        assert!((plain.get(w / 2, h / 2)[0] - bg).abs() > 0.02);
        for (x, y) in [(0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)] {
            assert!((plain.get(x, y)[0] - bg).abs() < 1e-3);
        }
        // With UVs the checker's dark squares (0.05) show: far darker pixels appear.
        let checker = render_preview(&quad(true), None, w, h).unwrap();
        let darkest = |img: &Image| img.pixels.iter().map(|p| p[0]).fold(1.0f32, f32::min);
        assert!(darkest(&checker) < 0.1 && darkest(&plain) > 0.1);
        let empty = Arc::new(Mesh::from_triangles(vec![], &[]).unwrap());
        assert!(render_preview(&empty, None, w, h).is_err());
    }

    #[test]
    fn the_bounding_sphere_fits_the_view() {
        let f = Framing {
            center: [1.0, 2.0, 3.0],
            radius: 2.0,
        };
        let cam = preview_camera(&f, 100, 50);
        let d: f64 = (0..3)
            .map(|k| (cam.eye[k] - f.center[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        // The sphere's angular radius is within the narrower half field of view.
        let half_v = 15f64.to_radians();
        assert!((f.radius / d).asin() <= half_v + 1e-12);
        assert!(cam.near < d - f.radius && cam.far > d + f.radius);
    }
}
