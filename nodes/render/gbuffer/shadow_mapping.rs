//! `shadow_mapping`: the shadow maps of a scene's lights as depth images (Williams,
//! "Casting Curved Shadows on Curved Surfaces", SIGGRAPH 1978), Framework3D's
//! `render_shadow_mapping` (`shadow_mapping.fs` writes each light's clip-space depth into
//! one layer of a texture array). The maps are the rasterizer's own (`raster/shadow.rs`):
//! a directional light gets one orthographic map fitted to the scene's bounding box, a
//! point light a cube of six 90-degree faces at half the resolution (stacked top to bottom
//! +X, -X, +Y, -Y, +Z, -Z into one image `res/2` wide and `3 res` high). Each texel holds
//! the nearest light-space depth (`+inf` where nothing is), so `deferred_lighting` rebuilds
//! the map from the image, the light and the scene's bounds (`map_from_image`).
//! Environment lights have no map: their entry is a 0 x 0 image.

use crate::raster::shadow::{
    cube_axes, directional_frame, directional_shadow_map, point_shadow_map, Face, ShadowMap,
};
use cgnodes_api::prelude::*;
use cgnodes_api::types::vec3::{dot, sub};
use cgnodes_geometry::scene_geometry::scene_geometry;

/// The cube faces' near distance for a scene of diagonal `diag` (as `render_raster`).
fn near_of(diag: f64) -> f64 {
    (1e-5 * diag).max(1e-9)
}

/// An axis-aligned box (low and high corners).
type Bounds = ([f64; 3], [f64; 3]);
/// World-space triangles.
type Tris = Vec<[[f64; 3]; 3]>;

/// Why shadow maps cannot be made from a scene or rebuilt from their images.
#[derive(Debug, thiserror::Error)]
pub enum ShadowMapError {
    /// The scene cannot be flattened to triangles (non-finite geometry).
    #[error("{0}")]
    Geometry(crate::BoxedError),
    /// The image's pixel buffer does not hold width x height pixels.
    #[error("pixel count differs from width x height")]
    PixelCount,
    /// A directional light's map image is not square.
    #[error("a directional light's map is square, not {width}x{height}")]
    NotSquare { width: u32, height: u32 },
    /// A point light's map image is not six square faces stacked.
    #[error("a point light's map is six square faces ({width}x{}), not {width}x{height}", 6 * width)]
    NotCube { width: u32, height: u32 },
    /// A map image was given for an environment light.
    #[error("an environment light has no shadow map")]
    Environment,
}

/// The scene's triangles and bounding box, flattened as the rasterizer does.
fn tris_and_bounds(scene: &Scene) -> Result<(Tris, Bounds), ShadowMapError> {
    let g = scene_geometry(scene).map_err(|e| ShadowMapError::Geometry(e.into()))?;
    Ok((g.pos, g.bounds))
}

/// The bounding box `render_raster` fits directional shadow maps to.
pub fn scene_bounds(scene: &Scene) -> Result<Bounds, ShadowMapError> {
    Ok(tris_and_bounds(scene)?.1)
}

/// One depth image per light of `scene` (see the module doc): `res` x `res` for a
/// directional light, six `res/2` faces for a point light, 0 x 0 for an environment light
/// or an empty scene. Fails on non-finite geometry.
pub fn shadow_maps(scene: &Scene, res: u32) -> Result<Vec<Image>, ShadowMapError> {
    use rayon::prelude::*;
    let (tris, bounds) = tris_and_bounds(scene)?;
    let d = sub(bounds.1, bounds.0);
    let diag = dot(d, d).sqrt();
    Ok(scene
        .lights
        .par_iter()
        .map(|l| {
            if tris.is_empty() {
                return Image::new(0, 0, [0.0; 4]);
            }
            match l {
                Light::Directional { direction, .. } => {
                    map_to_image(&directional_shadow_map(&tris, *direction, bounds, res))
                }
                Light::Point { position, .. } => map_to_image(&point_shadow_map(
                    &tris,
                    *position,
                    (res / 2).max(16),
                    near_of(diag),
                )),
                Light::Environment { .. } => Image::new(0, 0, [0.0; 4]),
            }
        })
        .collect())
}

fn face_pixels(f: &Face) -> impl Iterator<Item = [f32; 4]> + '_ {
    f.depth.iter().map(|&d| [d, d, d, 1.0])
}

/// A shadow map's depths as an image (faces of a cube stacked top to bottom).
pub fn map_to_image(m: &ShadowMap) -> Image {
    match m {
        ShadowMap::Directional { face, res, .. } => Image {
            width: *res,
            height: *res,
            pixels: face_pixels(face).collect(),
        },
        ShadowMap::Point { faces, res } => Image {
            width: *res,
            height: 6 * *res,
            pixels: faces.iter().flat_map(face_pixels).collect(),
        },
    }
}

/// Rebuilds `light`'s shadow map from its depth image `img` (as `shadow_maps` wrote it)
/// and the scene bounds; `Ok(None)` for a 0 x 0 image (no map). Fails when the image's
/// shape does not fit the light.
pub fn map_from_image(
    img: &Image,
    light: &Light,
    bounds: ([f64; 3], [f64; 3]),
) -> Result<Option<ShadowMap>, ShadowMapError> {
    if img.width == 0 || img.height == 0 {
        return Ok(None);
    }
    let (w, h) = (img.width, img.height);
    if img.pixels.len() != w as usize * h as usize {
        return Err(ShadowMapError::PixelCount);
    }
    let depth = |rows: std::ops::Range<usize>| -> Vec<f32> {
        img.pixels[rows.start * w as usize..rows.end * w as usize]
            .iter()
            .map(|p| p[0])
            .collect()
    };
    match light {
        Light::Directional { direction, .. } => {
            if w != h {
                return Err(ShadowMapError::NotSquare {
                    width: w,
                    height: h,
                });
            }
            let (axes, x0, y1, k) = directional_frame(*direction, bounds, w);
            Ok(Some(ShadowMap::Directional {
                face: Box::new(Face {
                    axes,
                    origin: [0.0; 3],
                    depth: depth(0..h as usize),
                }),
                x0,
                y1,
                k,
                res: w,
            }))
        }
        Light::Point { position, .. } => {
            if h != 6 * w {
                return Err(ShadowMapError::NotCube {
                    width: w,
                    height: h,
                });
            }
            let axes = cube_axes();
            let faces: [Face; 6] = std::array::from_fn(|i| Face {
                axes: axes[i],
                origin: *position,
                depth: depth(i * w as usize..(i + 1) * w as usize),
            });
            Ok(Some(ShadowMap::Point {
                faces: Box::new(faces),
                res: w,
            }))
        }
        Light::Environment { .. } => Err(ShadowMapError::Environment),
    }
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Shadow maps of the scene's lights as depth images (Framework3D's render_shadow_mapping), for deferred_lighting.");
    b.add_input::<Scene>("scene")
        .doc("Meshes (the casters) and lights.");
    b.add_input::<i64>("resolution")
        .default(1024i64)
        .range(256.0, 4096.0)
        .doc("Directional map size; point-light cube faces use half of it (as render_raster).");
    b.add_output::<Vec<Image>>("shadows")
        .doc("One depth image per light, in the scene's light order (0x0 for environment lights).");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let scene: Arc<Scene> = ctx.input("scene")?;
    let res: i64 = ctx.input("resolution")?;
    if !(256..=4096).contains(&res) {
        return Err(NodeError::invalid("resolution", "must lie in 256..=4096"));
    }
    let what = format!("{} shadow maps of {res}x{res}", scene.lights.len());
    let bytes =
        cgnodes_api::node::bytes_of(&[scene.lights.len() as u64, res as u64, res as u64, 24]);
    ctx.reserve_bytes("resolution", &what, bytes)?;
    let maps =
        shadow_maps(&scene, res as u32).map_err(|e| NodeError::invalid("scene", e.to_string()))?;
    let maps: Vec<Arc<Image>> = maps.into_iter().map(Arc::new).collect();
    ctx.set_output("shadows", maps);
    Ok(())
}

/// Registers `shadow_mapping`.
pub fn register(r: &mut Registry) {
    r.add("shadow_mapping", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::shadow::ShadowParams;

    fn quad(y: f64, h: f64) -> Mesh {
        Mesh::from_triangles(
            vec![[-h, y, -h], [h, y, -h], [h, y, h], [-h, y, h]],
            &[[0, 2, 1], [0, 3, 2]],
        )
        .unwrap()
    }

    /// A map written to an image and rebuilt answers every visibility query as the map
    /// itself, for a directional and a point light.
    #[test]
    fn maps_round_trip_through_images() {
        let mut scene = Scene::default();
        for (y, h) in [(0.0, 2.0), (1.0, 0.5)] {
            scene.objects.push(SceneObject {
                mesh: Arc::new(quad(y, h)),
                material: None,
            });
        }
        scene.lights = vec![
            Light::Directional {
                direction: [0.1, -1.0, 0.2],
                color: [1.0; 3],
                intensity: 1.0,
            },
            Light::Point {
                position: [0.2, 3.0, 0.1],
                color: [1.0; 3],
                intensity: 1.0,
            },
        ];
        let imgs = shadow_maps(&scene, 256).unwrap();
        assert_eq!((imgs[0].width, imgs[0].height), (256, 256));
        assert_eq!((imgs[1].width, imgs[1].height), (128, 768));
        let (tris, bounds) = tris_and_bounds(&scene).unwrap();
        let direct = [
            directional_shadow_map(&tris, [0.1, -1.0, 0.2], bounds, 256),
            point_shadow_map(
                &tris,
                [0.2, 3.0, 0.1],
                128,
                near_of(dot(sub(bounds.1, bounds.0), sub(bounds.1, bounds.0)).sqrt()),
            ),
        ];
        let sp = ShadowParams {
            pcf_radius: 1,
            bias: 1.0,
            slope_bias: 1.5,
        };
        let up = [0.0, 1.0, 0.0];
        let mut shadowed = 0;
        for (i, l) in scene.lights.iter().enumerate() {
            let m = map_from_image(&imgs[i], l, bounds).unwrap().unwrap();
            for k in 0..200 {
                let p = [-1.9 + 0.019 * k as f64, 0.0, 1.3 - 0.013 * k as f64];
                let (ld, _) = crate::gbuffer::light_at(l, p).unwrap();
                let a = m.visibility(p, up, ld, &sp);
                assert_eq!(a, direct[i].visibility(p, up, ld, &sp));
                shadowed += (a == 0.0) as usize;
            }
        }
        // The blocker does shadow part of the ground.
        assert!(shadowed > 20, "{shadowed}");
        // A wrong shape is refused.
        assert!(map_from_image(&imgs[0], &scene.lights[1], bounds).is_err());
    }
}
