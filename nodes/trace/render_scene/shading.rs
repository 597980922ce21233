//! Per-triangle shading data of a flattened scene, made beside its BVH
//! (`RenderScene::with_crease` runs the two at once): materials, textures, corner normals
//! smoothed below the crease angle (the rasterizer's flattening, `scene_geometry_creased`),
//! corner UVs and tangents where textures read them, geometric normals, areas, and which
//! triangles shade flat.

use super::{Face, RMaterial, SceneError, Textures};
use crate::bvh::triangle_normal;
use crate::sampling::{dot, length, normalize, v3, V3};
use cgnodes_api::types::{Material, Scene};
use cgnodes_geometry::scene_geometry::{scene_geometry_creased, scene_shape_creased};
use cgnodes_geometry::texture::MipTexture;
use rayon::prelude::*;
use std::sync::Arc;

/// What `shading` makes, per triangle unless noted.
pub(super) struct Shading {
    /// Geometric normal, material and whether the triangle shades flat.
    pub faces: Vec<Face>,
    /// The materials (per material).
    pub materials: Vec<RMaterial>,
    /// Each material's textures (per material).
    pub textures: Vec<Textures>,
    /// Shading normals at the corners.
    pub corner_normals: Vec<[V3; 3]>,
    /// Corner UVs, when a material has a texture (else empty; NaN where a mesh has none).
    pub corner_uvs: Vec<[[f32; 2]; 3]>,
    /// Corner tangents, when a material has a normal map (else empty).
    pub corner_tangents: Vec<[[f64; 4]; 3]>,
    /// Area.
    pub areas: Vec<f32>,
}

/// The shading data of `scene`'s triangles `tris` (`scene_positions`' order, which the
/// flattening shares), normals smoothed below `crease_deg`.
pub(super) fn shading(
    scene: &Scene,
    crease_deg: f64,
    tris: &[[V3; 3]],
) -> Result<Shading, SceneError> {
    // Corner UVs and tangents are read only through textures.
    let g = if scene_has_textures(scene) {
        scene_geometry_creased(scene, crease_deg)
    } else {
        scene_shape_creased(scene, crease_deg)
    }?;
    debug_assert_eq!(tris.len(), g.mat.len(), "one walk over the objects");
    let tri_mat = g.mat;
    let materials: Vec<RMaterial> = g
        .materials
        .iter()
        .map(|m| RMaterial::from_material(m))
        .collect();
    let textures = textures(&g.materials);
    let any_nmap = textures.iter().any(|t| t.normal.is_some());
    let corner_normals: Vec<[V3; 3]> = g.nrm.par_iter().map(|t| t.map(v3)).collect();
    let any_tex = textures
        .iter()
        .any(|t| t.base.is_some() || t.normal.is_some());
    let corner_uvs = if any_tex {
        corner_uvs(&g.uv, &g.has_uv)
    } else {
        Vec::new()
    };
    let corner_tangents = if any_nmap { g.tan } else { Vec::new() };
    // A triangle shades flat when it is untextured and its corner normals are its own.
    let (faces, areas): (Vec<Face>, Vec<f32>) = tris
        .par_iter()
        .zip(&corner_normals)
        .zip(&tri_mat)
        .map(|((t, c), &m)| {
            let cross = triangle_normal(t);
            let n = normalize(cross);
            let tx = &textures[m as usize];
            let plain = tx.base.is_none()
                && tx.normal.is_none()
                && c.iter().all(|&k| dot(k, n) >= 1.0 - 2e-7);
            (Face::new(n, m, plain), 0.5 * length(cross))
        })
        .unzip();
    Ok(Shading {
        faces,
        materials,
        textures,
        corner_normals,
        corner_uvs,
        corner_tangents,
        areas,
    })
}

/// Whether a material the scene's objects may take (the object's or its mesh's) has a
/// texture or a normal map.
fn scene_has_textures(scene: &Scene) -> bool {
    let textured = |m: &Arc<Material>| m.base_color_texture.is_some() || m.normal_map.is_some();
    scene.objects.iter().any(|o| {
        let m = o.material.iter().chain(o.mesh.material.iter());
        m.into_iter().any(textured)
    })
}

/// Each material's textures, sampled without mipmaps.
fn textures(materials: &[std::sync::Arc<Material>]) -> Vec<Textures> {
    materials
        .iter()
        .map(|m| Textures {
            base: m
                .base_color_texture
                .as_deref()
                .map(|i| MipTexture::new(i, false)),
            normal: m.normal_map.as_deref().map(|i| MipTexture::new(i, false)),
        })
        .collect()
}

/// Per-triangle corner UVs in `f32`; NaN marks a triangle without UVs.
fn corner_uvs(uv: &[[[f64; 2]; 3]], has_uv: &[bool]) -> Vec<[[f32; 2]; 3]> {
    uv.par_iter()
        .zip(has_uv)
        .map(|(t, &h)| {
            t.map(|w| {
                if h {
                    [w[0] as f32, w[1] as f32]
                } else {
                    [f32::NAN; 2]
                }
            })
        })
        .collect()
}
