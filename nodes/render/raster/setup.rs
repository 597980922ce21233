//! The rasterizer's setup stage: every triangle transformed to camera space, clipped
//! against the near and far planes, set up for rasterization in homogeneous pixel
//! coordinates (`rasterize::setup_triangle`) and binned into bands of sample rows; and the
//! materials prepared for shading (mipmapped textures, Blinn-Phong parameters).

use super::geometry::SceneGeometry;
use super::rasterize::{bin_rows, setup_triangle, TriSetup};
use super::scratch::{NORMALS, SETUPS};
use super::shader::MatPrep;
use super::shading;
use super::texture::MipTexture;
use cgnodes_api::prelude::*;
use cgnodes_api::types::vec3::{cross, normalize_recip as normalize, sub};
use rayon::prelude::*;

/// The camera's triangle setups (`None` for culled or clipped triangles), unit geometric
/// normals and the triangles of each band of `band_rows` sample rows.
pub(super) type CameraSetup = (Vec<Option<TriSetup>>, Vec<Option<[f64; 3]>>, Vec<Vec<u32>>);

/// Sets up the triangles of `g` seen through `cam` at `s x s` samples per pixel (the camera
/// must have passed `Camera::check`).
pub(super) fn camera_setup(
    g: &SceneGeometry,
    cam: &Camera,
    s: u32,
    band_rows: u32,
    cull_backfaces: bool,
) -> CameraSetup {
    let (ws, hs) = (cam.width * s, cam.height * s);
    let view = cam.look_at::<f64>();
    let f = cam.focal_length_px() * s as f64;
    let (cx, cy) = (ws as f64 * 0.5, hs as f64 * 0.5);
    // Buffers kept from earlier renders (`scratch`), written in place.
    let mut setups = SETUPS.take(g.pos.len());
    let mut ngs = NORMALS.take(g.pos.len());
    g.pos
        .par_iter()
        .map(|t| {
            let c = t.map(|p| view.to_view(p));
            if c.iter().all(|v| v[2] < cam.near) || c.iter().all(|v| v[2] > cam.far) {
                return (None, None);
            }
            let hh = c.map(|v| [cx * v[2] + f * v[0], cy * v[2] - f * v[1], v[2]]);
            let Some(st) = setup_triangle(hh, c.map(|v| v[2]), cam.near, ws, hs) else {
                return (None, None);
            };
            // det M < 0 is counter-clockwise seen from the eye (the camera frame is
            // left-handed and the pixel y axis points down: two sign flips and f^2 > 0).
            if cull_backfaces && !st.det_negative {
                return (None, None);
            }
            let ng = normalize(cross(sub(t[1], t[0]), sub(t[2], t[0])));
            (Some(st), ng)
        })
        .unzip_into_vecs(&mut setups, &mut ngs);
    let bins = bin_rows(&setups, hs, band_rows);
    (setups, ngs, bins)
}

/// The materials of `g` ready for shading.
pub(super) fn prepare_materials(g: &SceneGeometry, mipmaps: bool) -> Vec<MatPrep> {
    g.materials
        .iter()
        .map(|m| MatPrep {
            base: m.base_color,
            tex: m
                .base_color_texture
                .as_ref()
                .map(|t| MipTexture::new(t, mipmaps)),
            nmap: m.normal_map.as_ref().map(|t| MipTexture::new(t, mipmaps)),
            ks: shading::specular_weight(m.metallic),
            k: shading::roughness_to_exponent(m.roughness),
            emission: m.emission,
        })
        .collect()
}
