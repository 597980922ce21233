//! The renderer's view of a `Scene`: every object triangulated into one f32 triangle list
//! with a BVH over it, compact per-triangle materials, the emissive triangles with a
//! distribution for sampling them by power (area times emitted luminance), and a pinhole
//! camera that turns film positions into rays. Shared by `render_path` and `render_whitted`.

use super::bsdf::Bsdf;
use super::bvh::{Bvh, Hit};
pub use super::camera::PinholeCamera;
use super::environment::Environment;
use super::sampling::{
    add, dot, length, luminance, max_comp, normalize, scale, sub, uniform_triangle, v3, AliasTable,
    V3,
};
pub use super::trace_error::{SceneError, TraceError};
use cgnodes_api::types::{Light, Material, MaterialKind, Scene};
use cgnodes_geometry::scene_geometry::{normal_mapped, scene_positions};
use cgnodes_geometry::texture::{MipTexture, Wrap};

mod prepare;
mod shading;
pub use prepare::{prepare, prepare_cached};

/// A material reduced to what the tracers evaluate.
#[derive(Clone, Debug)]
pub struct RMaterial {
    /// Scattering model.
    pub bsdf: Bsdf,
    /// Diffuse albedo / specular tint (linear RGB).
    pub albedo: V3,
    /// Emitted radiance.
    pub emission: V3,
    /// Whether emission leaves both faces (otherwise only the front, where the winding is
    /// counter-clockwise).
    pub two_sided_emission: bool,
    /// Phong exponent for the Whitted tracer, from roughness (shininess = 2 / r^2 - 2).
    pub shininess: f32,
    /// Phong specular weight for the Whitted tracer (`metallic`, floor 0.04 when rough < 1).
    pub specular: f32,
}

impl RMaterial {
    /// Converts a scene material.
    pub fn from_material(m: &Material) -> RMaterial {
        let bsdf = match m.kind {
            MaterialKind::Diffuse => Bsdf::Diffuse,
            MaterialKind::Mirror => Bsdf::Mirror,
            MaterialKind::Dielectric { ior } => Bsdf::Dielectric {
                eta: if ior.is_finite() && ior > 0.0 {
                    ior as f32
                } else {
                    1.5
                },
            },
            MaterialKind::Conductor { roughness } => {
                let r = if roughness.is_finite() {
                    roughness.clamp(0.0, 1.0) as f32
                } else {
                    0.5
                };
                if r < 1e-3 {
                    Bsdf::Mirror
                } else {
                    // alpha = roughness^2 (Burley 2012 remapping).
                    Bsdf::Conductor {
                        alpha: (r * r).max(1e-3),
                    }
                }
            }
        };
        let clean = |c: [f64; 3], hi: f64| {
            let mut o = v3(c);
            for x in &mut o {
                *x = if x.is_finite() {
                    x.clamp(0.0, hi as f32)
                } else {
                    0.0
                };
            }
            o
        };
        let r = if m.roughness.is_finite() {
            m.roughness.clamp(0.02, 1.0) as f32
        } else {
            0.5
        };
        RMaterial {
            bsdf,
            albedo: clean(m.base_color, 1.0),
            emission: clean(m.emission, f64::MAX),
            two_sided_emission: m.two_sided_emission,
            shininess: (2.0 / (r * r) - 2.0).max(1.0),
            specular: if m.metallic.is_finite() {
                (m.metallic as f32).clamp(0.04, 1.0)
            } else {
                0.04
            },
        }
    }

    /// Whether the surface emits.
    pub fn is_emitter(&self) -> bool {
        max_comp(self.emission) > 0.0
    }
}

/// The crease angle (degrees) below which computed vertex normals smooth across an edge:
/// a tessellated sphere shades smooth, a box keeps its edges.
pub const DEFAULT_CREASE_DEG: f64 = 60.0;

/// A material's textures, sampled bilinearly through the mesh's UVs (repeating), as the
/// rasterizer samples them when magnified.
#[derive(Clone, Debug, Default)]
pub struct Textures {
    /// Base colour, multiplying the albedo.
    pub base: Option<MipTexture>,
    /// Tangent-space normal map.
    pub normal: Option<MipTexture>,
}

/// The surface at a hit as the shaders see it.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// Unit geometric normal (counter-clockwise side).
    pub ng: V3,
    /// Unit shading normal (interpolated, normal-mapped), on the side of `ng`.
    pub ns: V3,
    /// Albedo times the texture.
    pub albedo: V3,
}

/// A point on an emissive triangle sampled for next-event estimation.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// The point.
    pub p: V3,
    /// Unit geometric normal there.
    pub n: V3,
    /// Triangle index.
    pub tri: u32,
    /// Density per unit area (selection probability over the triangle's area).
    pub pdf_area: f32,
    /// The triangle's emitted radiance (toward its front, or both sides).
    pub le: V3,
    /// Whether it emits on both sides.
    pub two_sided: bool,
}

impl LightSample {
    /// Emitted radiance toward unit direction `w` (pointing away from the light):
    /// `RenderScene::emitted` from the sample's own record.
    #[inline(always)]
    pub fn emitted(&self, w: V3) -> V3 {
        if self.two_sided || dot(self.n, w) > 0.0 {
            self.le
        } else {
            [0.0; 3]
        }
    }
}

/// An emissive triangle as light sampling reads it: corners, normal, density and
/// emission in one record, so that a sample touches nothing else (the chain of look-ups
/// through triangle, normal, density and material arrays was about a tenth of the box
/// render's time: docs/path_tracing.md, "How it runs").
#[derive(Clone, Copy, Debug)]
pub struct EmitterRecord {
    /// Corners.
    pub corners: [V3; 3],
    /// Unit geometric normal.
    pub n: V3,
    /// Triangle index.
    pub tri: u32,
    /// Density per unit area of sampling a point on it.
    pub pdf_area: f32,
    /// Emitted radiance.
    pub le: V3,
    /// Whether it emits on both sides.
    pub two_sided: bool,
}

/// The part of a point's largest coordinate added to `RenderScene::eps` when a ray leaves
/// a surface (`RenderScene::offset`): f32 round-off grows with the coordinates.
pub const OFFSET_REL: f32 = 4e-7;

/// Where a shadow segment `o + t (q - o)` towards a light point `q` stops: short of the
/// point, so the light's own surface does not block it.
pub const SHADOW_END: f32 = 1.0 - 1e-4;

/// What a hit on a triangle reads first, in one 16-byte record (one cache line, one bounds
/// check): its unit geometric normal (counter-clockwise winding), its material, and
/// whether its shading point is that normal and the material's albedo (corner normals
/// within 2e-7 of the normal's direction, no texture or normal map), so that `surface`
/// skips the interpolation: every triangle of a flat-shaded scene.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct Face {
    /// Unit geometric normal.
    pub n: V3,
    /// The material index, with `PLAIN` set when the triangle shades flat.
    word: u32,
}

/// `Face::word`'s flat-shading bit (material indices stay below it: a scene cannot hold
/// 2^31 materials).
const PLAIN: u32 = 1 << 31;

impl Face {
    /// The record of a triangle with normal `n`, material `mat` (below 2^31).
    pub fn new(n: V3, mat: u32, plain: bool) -> Face {
        debug_assert!(mat < PLAIN, "material index {mat} over 2^31");
        Face {
            n,
            word: (mat & !PLAIN) | if plain { PLAIN } else { 0 },
        }
    }

    /// The material index.
    #[inline(always)]
    pub fn material(self) -> usize {
        (self.word & !PLAIN) as usize
    }

    /// Whether the triangle shades flat (`RenderScene::surface` then skips interpolating).
    #[inline(always)]
    pub fn plain(self) -> bool {
        self.word & PLAIN != 0
    }
}

/// The flattened scene.
#[derive(Clone, Debug)]
pub struct RenderScene {
    /// BVH over every triangle.
    pub bvh: Bvh,
    /// Triangle corners, in the caller's order (index = `Hit::prim`).
    pub tris: Vec<[V3; 3]>,
    /// Per triangle, what every hit reads first (`RenderScene::face`): the geometric
    /// normal, the material and whether it shades flat.
    pub faces: Vec<Face>,
    /// Unit shading normals at each triangle's corners.
    pub corner_normals: Vec<[V3; 3]>,
    /// UVs at each triangle's corners (NaN when its mesh has none); empty when no material
    /// has a texture, since only textures read them.
    pub corner_uvs: Vec<[[f32; 2]; 3]>,
    /// Tangents with handedness at each triangle's corners (empty when no material has a
    /// normal map).
    pub corner_tangents: Vec<[[f64; 4]; 3]>,
    /// Textures per material.
    pub textures: Vec<Textures>,
    /// Materials.
    pub materials: Vec<RMaterial>,
    /// Emissive triangles.
    pub emitters: Vec<u32>,
    /// Emitter distribution over `emitters` (area times luminance of the emission).
    pub emitter_table: AliasTable,
    /// What sampling a point on `emitters[k]` reads, in one record per emitter.
    pub emitter_recs: Vec<EmitterRecord>,
    /// Per triangle: density per unit area of sampling a point on it (0 for non-emitters).
    pub light_pdf_area: Vec<f32>,
    /// Point and directional lights.
    pub lights: Vec<Light>,
    /// The environment light (the scene's first), if any.
    pub env: Option<Environment>,
    /// Ray offset length for leaving a surface (relative to the scene's size).
    pub eps: f32,
}

impl RenderScene {
    /// Flattens `scene` with the default crease angle (`DEFAULT_CREASE_DEG`).
    pub fn new(scene: &Scene) -> Result<RenderScene, SceneError> {
        RenderScene::with_crease(scene, DEFAULT_CREASE_DEG)
    }

    /// Flattens `scene`: triangulates every object, resolves materials (the object's, else
    /// the mesh's, else the default grey diffuse) and builds the BVH and emitter table.
    /// Corner normals, UVs and tangents come from the rasterizer's flattening
    /// (`scene_geometry_creased`): the mesh's own normals, else normals smoothed across
    /// edges whose dihedral angle is below `crease_deg` (0 = flat shading).
    pub fn with_crease(scene: &Scene, crease_deg: f64) -> Result<RenderScene, SceneError> {
        check_scene(scene, crease_deg)?;
        // The BVH is built on the bare positions while the corner attributes are flattened
        // and turned into shading data: its build has serial stretches that the other core
        // fills.
        let tris = scene_positions(scene);
        let (bvh, sh) = rayon::join(
            || Bvh::build(&tris),
            || shading::shading(scene, crease_deg, &tris),
        );
        let sh = sh?;
        let em = EmitterTables::new(&tris, &sh.faces, &sh.areas, &sh.materials);
        let b = bvh.bounds();
        let diag = if tris.is_empty() {
            1.0
        } else {
            length(sub(b.max, b.min))
        };
        let lights = delta_lights(&scene.lights)?;
        let env = Environment::from_lights(&scene.lights);
        Ok(RenderScene {
            bvh,
            tris,
            faces: sh.faces,
            corner_normals: sh.corner_normals,
            corner_uvs: sh.corner_uvs,
            corner_tangents: sh.corner_tangents,
            textures: sh.textures,
            materials: sh.materials,
            emitters: em.emitters,
            emitter_table: em.table,
            emitter_recs: em.records,
            light_pdf_area: em.light_pdf_area,
            lights,
            env,
            eps: 1e-5 * diag.max(1e-3),
        })
    }

    /// Closest hit.
    #[inline]
    pub fn intersect(&self, org: V3, dir: V3, tmax: f32) -> Option<Hit> {
        self.bvh.intersect(org, dir, tmax)
    }

    /// The face record of triangle `tri`.
    #[inline(always)]
    pub fn face(&self, tri: u32) -> Face {
        self.faces[tri as usize]
    }

    /// The unit geometric normal of triangle `tri` (counter-clockwise winding).
    #[inline]
    pub fn normal(&self, tri: u32) -> V3 {
        self.faces[tri as usize].n
    }

    /// The material of triangle `tri`.
    #[inline]
    pub fn material(&self, tri: u32) -> &RMaterial {
        &self.materials[self.face(tri).material()]
    }

    /// The shading normal and textured albedo of the surface at `hit`: the corner normals
    /// interpolated with the hit's barycentrics (Phong 1975), perturbed by the normal map,
    /// and kept on the geometric normal's side (a shading normal facing away from the
    /// geometric one would light the back of the surface).
    #[inline(always)]
    pub fn surface(&self, hit: &Hit) -> SurfacePoint {
        let f = self.face(hit.prim);
        self.surface_on(hit, f, &self.materials[f.material()])
    }

    /// `surface` for a caller that already holds the hit triangle's face and material.
    #[inline(always)]
    pub fn surface_on(&self, hit: &Hit, f: Face, mat: &RMaterial) -> SurfacePoint {
        if f.plain() {
            return SurfacePoint {
                ng: f.n,
                ns: f.n,
                albedo: mat.albedo,
            };
        }
        self.surface_interpolated(hit, f)
    }

    /// `surface` for a triangle that is not plain (its own call: inlining it into every
    /// caller would crowd the flat-shaded case).
    #[inline(never)]
    fn surface_interpolated(&self, hit: &Hit, f: Face) -> SurfacePoint {
        let ng = f.n;
        let t = hit.prim as usize;
        let (b1, b2) = (hit.u, hit.v);
        let b0 = 1.0 - b1 - b2;
        let c = &self.corner_normals[t];
        let lerp = |k: usize| b0 * c[0][k] + b1 * c[1][k] + b2 * c[2][k];
        let mut ns = normalize([lerp(0), lerp(1), lerp(2)]);
        let m = f.material();
        let mut albedo = self.materials[m].albedo;
        let tx = &self.textures[m];
        // Corner UVs are kept when a material has a texture (NaN where a mesh has none).
        let uv = self.corner_uvs.get(t).filter(|w| !w[0][0].is_nan());
        if let (true, Some(w)) = (tx.base.is_some() || tx.normal.is_some(), uv) {
            let u = (b0 * w[0][0] + b1 * w[1][0] + b2 * w[2][0]) as f64;
            let v = (b0 * w[0][1] + b1 * w[1][1] + b2 * w[2][1]) as f64;
            if let Some(tex) = &tx.base {
                let c = tex.bilinear(0, u, v, Wrap::Repeat);
                albedo = [albedo[0] * c[0], albedo[1] * c[1], albedo[2] * c[2]];
            }
            if let (Some(nm), Some(tan)) = (&tx.normal, self.corner_tangents.get(t)) {
                let c = nm.bilinear(0, u, v, Wrap::Repeat);
                let n64 = ns.map(|x| x as f64);
                let b = [b0 as f64, b1 as f64, b2 as f64];
                if let Some(n) = normal_mapped(n64, tan, b, c) {
                    ns = v3(n);
                }
            }
        }
        let d = dot(ns, ng);
        if !d.is_finite() || (length(ns) - 1.0).abs() > 1e-3 {
            ns = ng;
        } else if d < 0.0 {
            ns = scale(ns, -1.0);
        }
        SurfacePoint { ng, ns, albedo }
    }

    /// A surface point moved off the surface along `n` (to the side a new ray leaves
    /// from), so the new ray does not hit the surface it starts on.
    #[inline]
    pub fn offset(&self, p: V3, n: V3) -> V3 {
        let m = p[0].abs().max(p[1].abs()).max(p[2].abs());
        add(p, scale(n, self.eps + OFFSET_REL * m))
    }

    /// Samples a point on the emitters by power (one triangle by area times luminance,
    /// then uniformly on it; Shirley et al. 1996, "Monte Carlo techniques for direct
    /// lighting calculations").
    #[inline(always)]
    pub fn sample_emitter(&self, u: f32, uv: [f32; 2]) -> Option<LightSample> {
        if self.emitter_table.is_empty() {
            return None;
        }
        let e = &self.emitter_recs[self.emitter_table.sample(u)];
        let t = &e.corners;
        let (b1, b2) = uniform_triangle(uv);
        let p = add(
            add(scale(t[0], 1.0 - b1 - b2), scale(t[1], b1)),
            scale(t[2], b2),
        );
        Some(LightSample {
            p,
            n: e.n,
            tri: e.tri,
            pdf_area: e.pdf_area,
            le: e.le,
            two_sided: e.two_sided,
        })
    }

    /// Emitted radiance of triangle `tri` toward unit direction `w` (pointing away from it).
    #[inline]
    pub fn emitted(&self, tri: u32, w: V3) -> V3 {
        let m = self.material(tri);
        if !m.is_emitter() {
            return [0.0; 3];
        }
        if m.two_sided_emission || dot(self.normal(tri), w) > 0.0 {
            m.emission
        } else {
            [0.0; 3]
        }
    }
}

/// Refuses a scene the tracers cannot build: non-finite vertices, faces with a bad vertex
/// index, a crease angle outside 0..=180 degrees.
fn check_scene(scene: &Scene, crease_deg: f64) -> Result<(), SceneError> {
    for (oi, obj) in scene.objects.iter().enumerate() {
        let mesh = &obj.mesh;
        for (vi, p) in mesh.positions.iter().enumerate() {
            if !p.iter().all(|x| x.is_finite()) {
                return Err(SceneError::NonFiniteVertex {
                    object: oi,
                    vertex: vi,
                });
            }
        }
        let n = mesh.positions.len() as u32;
        if mesh
            .faces()
            .any(|f| f.len() < 3 || f.iter().any(|&i| i >= n))
        {
            return Err(SceneError::BadFace { object: oi });
        }
    }
    if !(0.0..=180.0).contains(&crease_deg) {
        return Err(SceneError::Crease(crease_deg));
    }
    Ok(())
}

/// The emissive triangles and how next-event estimation picks them: in proportion to area
/// times luminance (times two when both sides emit), through an alias table.
struct EmitterTables {
    emitters: Vec<u32>,
    table: AliasTable,
    records: Vec<EmitterRecord>,
    /// Per triangle: the area density of picking a point on it (0 for non-emitters).
    light_pdf_area: Vec<f32>,
}

impl EmitterTables {
    fn new(
        tris: &[[V3; 3]],
        faces: &[Face],
        areas: &[f32],
        materials: &[RMaterial],
    ) -> EmitterTables {
        let mut emitters = Vec::new();
        let mut weights = Vec::new();
        for (i, f) in faces.iter().enumerate() {
            let mat = &materials[f.material()];
            if mat.is_emitter() && areas[i] > 0.0 {
                emitters.push(i as u32);
                let sides = if mat.two_sided_emission { 2.0 } else { 1.0 };
                weights.push(areas[i] as f64 * sides * (luminance(mat.emission) as f64).max(1e-6));
            }
        }
        let table = AliasTable::new(&weights);
        let total: f64 = weights.iter().sum();
        let mut light_pdf_area = vec![0.0f32; tris.len()];
        let mut records = Vec::with_capacity(emitters.len());
        for (k, &e) in emitters.iter().enumerate() {
            let e = e as usize;
            light_pdf_area[e] = (weights[k] / total) as f32 / areas[e];
            let m = &materials[faces[e].material()];
            records.push(EmitterRecord {
                corners: tris[e],
                n: faces[e].n,
                tri: e as u32,
                pdf_area: light_pdf_area[e],
                le: m.emission,
                two_sided: m.two_sided_emission,
            });
        }
        EmitterTables {
            emitters,
            table,
            records,
            light_pdf_area,
        }
    }
}

/// The scene's point and directional lights, checked finite (environment lights are
/// sampled through `Environment`, not with the delta lights).
fn delta_lights(lights: &[Light]) -> Result<Vec<Light>, SceneError> {
    let mut out = Vec::new();
    for l in lights {
        match l {
            Light::Point {
                position,
                color,
                intensity,
            } => {
                if !position.iter().chain(color).all(|x| x.is_finite()) || !intensity.is_finite() {
                    return Err(SceneError::PointLight);
                }
            }
            Light::Directional {
                direction,
                color,
                intensity,
            } => {
                if !direction.iter().chain(color).all(|x| x.is_finite())
                    || !intensity.is_finite()
                    || direction.iter().all(|x| *x == 0.0)
                {
                    return Err(SceneError::DirectionalLight);
                }
            }
            Light::Environment { .. } => continue,
        }
        out.push(l.clone());
    }
    Ok(out)
}
