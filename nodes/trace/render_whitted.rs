//! `render_whitted`: the course's recursive ray tracer (Whitted 1980, "An Improved
//! Illumination Model for Shaded Display"): at each hit, local shading by every light with
//! shadow rays, using normalised Blinn-Phong (diffuse albedo/pi plus
//! ks (s+8)/(8 pi) (n.h)^s, Akenine-Moller et al., Real-Time Rendering, 4th ed., eq. 9.64),
//! plus recursive perfect reflection (mirrors, tinted by the albedo; conductors) and
//! refraction weighted by the exact Fresnel term (dielectrics).
//!
//! An environment light shows as the background and adds its mean radiance times the
//! diffuse albedo as ambient light (unshadowed). Shading uses the interpolated (and
//! normal-mapped) shading normal, on the viewer's side of the geometric one.
//!
//! Lights are the scene's point and directional lights, and every emissive triangle,
//! integrated with a fixed stratified grid of `light_samples` points per triangle (so the
//! image is deterministic and noise-free, with soft shadows from area lights). Emitters
//! seen directly show their radiance. `max_depth` counts ray segments as in `render_path`:
//! 1 shows only local shading of the first hit, each extra level allows one more
//! reflection or refraction.

use super::bsdf::{fresnel_dielectric, reflect, Bsdf};
use super::direct::delta_incidence;
use super::render_scene::{prepare_cached, PinholeCamera, RenderScene, TraceError, SHADOW_END};
use super::sampling::{add, dot, max_comp, mul, normalize, scale, sub, uniform_triangle, V3};
use super::tracer_node::{crease_input, declare_crease, reserve_image, trace_error};
use cgnodes_api::prelude::*;
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Whitted tracer settings.
#[derive(Clone, Debug)]
pub struct WhittedSettings {
    /// Longest ray tree branch in segments (camera ray = 1).
    pub max_depth: u32,
    /// Stratified sample points per emissive triangle (rounded down to a square).
    pub light_samples: u32,
    /// Ambient radiance added as `ambient * albedo` (the course's ambient term).
    pub ambient: f32,
    /// Rays per pixel edge (antialiasing grid `aa x aa`).
    pub aa: u32,
    /// Crease angle in degrees for computed vertex normals (0 = flat shading).
    pub crease_deg: f64,
}

impl Default for WhittedSettings {
    fn default() -> Self {
        WhittedSettings {
            max_depth: 8,
            light_samples: 16,
            ambient: 0.0,
            aa: 2,
            crease_deg: super::render_scene::DEFAULT_CREASE_DEG,
        }
    }
}

/// Stratified barycentric points on a triangle: an n x n grid of cell centres mapped with
/// the uniform triangle map, so each point stands for area / n^2.
fn light_points(n: u32) -> Vec<(f32, f32)> {
    let mut pts = Vec::with_capacity((n * n) as usize);
    for i in 0..n {
        for j in 0..n {
            pts.push(uniform_triangle([
                (i as f32 + 0.5) / n as f32,
                (j as f32 + 0.5) / n as f32,
            ]));
        }
    }
    pts
}

/// Radiance toward `-dir` by Whitted's recursion.
pub fn trace(
    sc: &RenderScene,
    pts: &[(f32, f32)],
    org: V3,
    dir: V3,
    depth: u32,
    s: &WhittedSettings,
) -> V3 {
    let Some(hit) = sc.intersect(org, dir, f32::INFINITY) else {
        // The environment shows as the background.
        return sc.env.as_ref().map_or([0.0; 3], |e| e.eval(dir));
    };
    let tri = hit.prim;
    let mat = sc.material(tri);
    let sp = sc.surface(&hit);
    let ng = sp.ng;
    let wo = scale(dir, -1.0);
    let p = add(org, scale(dir, hit.t));
    // Geometric normal on the viewer's side (offsets, visibility) and the shading normal
    // with it (lighting, reflection), replaced by the geometric one when the viewer is
    // below it; reflections the shading normal sends under the surface use the geometric
    // normal instead (no light leaks).
    let n = if dot(ng, wo) < 0.0 {
        scale(ng, -1.0)
    } else {
        ng
    };
    let mut ns = scale(sp.ns, dot(n, ng));
    if dot(ns, wo) <= 1e-4 {
        ns = n;
    }
    let mut l = sc.emitted(tri, wo);
    let recurse = depth < s.max_depth;
    match mat.bsdf {
        Bsdf::Mirror => {
            if recurse {
                let mut wi = reflect(wo, ns);
                if dot(wi, n) <= 0.0 {
                    wi = reflect(wo, n);
                }
                let li = trace(sc, pts, sc.offset(p, n), wi, depth + 1, s);
                l = add(l, mul(sp.albedo, li));
            }
            return l;
        }
        Bsdf::Dielectric { eta } => {
            if recurse {
                let hp = HitPoint { p, wo, ng, n, ns };
                l = add(l, dielectric(sc, pts, &hp, eta, depth, s));
            }
            return l;
        }
        _ => {}
    }
    // Local shading.
    let conductor = matches!(mat.bsdf, Bsdf::Conductor { .. });
    let sh = mat.shininess;
    let local = Phong {
        p,
        o: sc.offset(p, n),
        wo,
        n,
        ns,
        kd: if conductor { [0.0; 3] } else { sp.albedo },
        ks: if conductor {
            sp.albedo
        } else {
            [mat.specular; 3]
        },
        sh,
        norm: (sh + 8.0) / (8.0 * std::f32::consts::PI),
    };
    // Ambient: the constant term plus the environment's mean radiance (what a Lambertian
    // surface open to the whole sky reflects, unshadowed).
    let amb = sc.env.as_ref().map_or([0.0; 3], |e| e.mean());
    l = add(l, mul(local.kd, add([s.ambient; 3], amb)));
    l = local.add_lights(sc, l);
    l = local.add_area_emitters(sc, pts, tri, l);
    let o = local.o;
    if recurse {
        if let Bsdf::Conductor { alpha } = mat.bsdf {
            // The smooth part of a conductor: a mirror bounce fading with roughness.
            let k = (1.0 - alpha.sqrt()).max(0.0);
            if k > 0.0 {
                let mut wi = reflect(wo, ns);
                if dot(wi, n) <= 0.0 {
                    wi = reflect(wo, n);
                }
                let li = trace(sc, pts, o, wi, depth + 1, s);
                l = add(l, scale(mul(sp.albedo, li), k));
            }
        }
    }
    l
}

/// A surface point a ray hit: position, direction to the viewer, geometric normal, the
/// geometric normal on the viewer's side `n`, and the shading normal `ns` on that side.
struct HitPoint {
    p: V3,
    wo: V3,
    ng: V3,
    n: V3,
    ns: V3,
}

/// The radiance a smooth dielectric sends toward the viewer: Fresnel-weighted reflection
/// plus refraction (Snell's law), each traced one level deeper. The shading normal is used
/// when both directions stay on their sides of the geometric surface, else the geometric one.
fn dielectric(
    sc: &RenderScene,
    pts: &[(f32, f32)],
    h: &HitPoint,
    eta: f32,
    depth: u32,
    s: &WhittedSettings,
) -> V3 {
    let (p, wo, n) = (h.p, h.wo, h.n);
    let eta_rel = if dot(h.ng, wo) > 0.0 { eta } else { 1.0 / eta };
    let ok = |m: V3| {
        let (_, cos_t) = fresnel_dielectric(dot(m, wo), eta_rel);
        let wt = add(
            scale(wo, -1.0 / eta_rel),
            scale(m, dot(m, wo) / eta_rel - cos_t),
        );
        dot(reflect(wo, m), n) > 0.0 && (cos_t == 0.0 || dot(wt, n) < 0.0)
    };
    let m = if ok(h.ns) { h.ns } else { n };
    let cos_i = dot(m, wo);
    let (f, cos_t) = fresnel_dielectric(cos_i, eta_rel);
    let wr = reflect(wo, m);
    let lr = trace(sc, pts, sc.offset(p, n), wr, depth + 1, s);
    let mut l = scale(lr, f);
    if f < 1.0 {
        let wt = normalize(add(
            scale(wo, -1.0 / eta_rel),
            scale(m, cos_i / eta_rel - cos_t),
        ));
        let lt = trace(sc, pts, sc.offset(p, scale(n, -1.0)), wt, depth + 1, s);
        // Radiance scales by 1/eta^2 across the interface (Veach 1997, 5.2).
        l = add(l, scale(lt, (1.0 - f) / (eta_rel * eta_rel)));
    }
    l
}

/// Normalized Blinn-Phong shading at a hit point (`kd / pi + ks (sh + 8) / (8 pi)
/// cos^sh`), with shadow rays from `o`, the point offset to the viewer's side.
struct Phong {
    p: V3,
    o: V3,
    wo: V3,
    n: V3,
    ns: V3,
    kd: V3,
    ks: V3,
    sh: f32,
    norm: f32,
}

impl Phong {
    /// Radiance reflected toward the viewer from irradiance `e` arriving along `wi`.
    fn shade(&self, wi: V3, e: V3) -> V3 {
        let c = dot(self.ns, wi);
        if c <= 0.0 || dot(self.n, wi) <= 0.0 {
            return [0.0; 3];
        }
        let h = normalize(add(wi, self.wo));
        let spec = self.norm * dot(self.ns, h).max(0.0).powf(self.sh);
        let f = add(scale(self.kd, FRAC_1_PI), scale(self.ks, spec));
        scale(mul(f, e), c)
    }

    /// `l` plus the light of the unshadowed point and directional lights.
    fn add_lights(&self, sc: &RenderScene, mut l: V3) -> V3 {
        let (p, o) = (self.p, self.o);
        for light in &sc.lights {
            let Some((wi, e, target)) = delta_incidence(light, p) else {
                continue;
            };
            let blocked = match target {
                Some(lp) => sc.bvh.occluded(o, sub(lp, o), SHADOW_END),
                None => sc.bvh.occluded(o, wi, f32::INFINITY),
            };
            if !blocked {
                l = add(l, self.shade(wi, e));
            }
        }
        l
    }

    /// `l` plus the light of the area emitters other than triangle `tri`, by a fixed
    /// quadrature over each emissive triangle at the barycentric points `pts`.
    fn add_area_emitters(&self, sc: &RenderScene, pts: &[(f32, f32)], tri: u32, mut l: V3) -> V3 {
        let (p, o, n, ns) = (self.p, self.o, self.n, self.ns);
        for &e in &sc.emitters {
            if e == tri {
                continue;
            }
            let t = &sc.tris[e as usize];
            let ln = sc.normal(e);
            let area = 0.5 * super::sampling::length(super::bvh::triangle_normal(t));
            let w = area / pts.len() as f32;
            for &(b1, b2) in pts {
                let q = add(
                    add(scale(t[0], 1.0 - b1 - b2), scale(t[1], b1)),
                    scale(t[2], b2),
                );
                let d = sub(q, p);
                let r2 = dot(d, d);
                if r2 <= 0.0 {
                    continue;
                }
                let wi = scale(d, 1.0 / r2.sqrt());
                let le = sc.emitted(e, scale(wi, -1.0));
                let cl = dot(ln, wi).abs();
                if max_comp(le) <= 0.0 || dot(n, wi) <= 0.0 || dot(ns, wi) <= 0.0 {
                    continue;
                }
                if !sc.bvh.occluded(o, sub(q, o), SHADOW_END) {
                    l = add(l, self.shade(wi, scale(le, w * cl / r2)));
                }
            }
        }
        l
    }
}

/// Renders `cam`'s view of `sc` (linear radiance).
pub fn render(
    sc: &RenderScene,
    cam: &PinholeCamera,
    s: &WhittedSettings,
    progress: &(dyn Fn(f64) + Sync),
) -> Image {
    let n = (s.light_samples as f32).sqrt().floor().max(1.0) as u32;
    let pts = light_points(n);
    let (w, h) = (cam.width, cam.height);
    let done = AtomicUsize::new(0);
    let aa = s.aa.max(1);
    let rows: Vec<Vec<[f32; 4]>> = (0..h)
        .into_par_iter()
        .map(|y| {
            let row = (0..w)
                .map(|x| {
                    let mut c = [0.0f32; 3];
                    for i in 0..aa {
                        for j in 0..aa {
                            let fx = x as f32 + (j as f32 + 0.5) / aa as f32;
                            let fy = y as f32 + (i as f32 + 0.5) / aa as f32;
                            let li = trace(sc, &pts, cam.eye, cam.ray_dir(fx, fy), 1, s);
                            c = add(c, li);
                        }
                    }
                    let k = 1.0 / (aa * aa) as f32;
                    [c[0] * k, c[1] * k, c[2] * k, 1.0]
                })
                .collect();
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress(d as f64 / h as f64);
            row
        })
        .collect();
    Image {
        width: w,
        height: h,
        pixels: rows.into_iter().flatten().collect(),
    }
}

/// Flattens `scene` and renders it from `camera` (or the scene's camera).
pub fn render_whitted(
    scene: &Scene,
    camera: Option<&Camera>,
    s: &WhittedSettings,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<Image, TraceError> {
    let (sc, cam, _) = prepare_cached(scene, camera, s.crease_deg)?;
    Ok(render(&sc, &cam, s, progress))
}

fn declare(b: &mut NodeBuilder) {
    b.doc(
        "Whitted ray tracing: Blinn-Phong with shadow rays, mirror reflection, Fresnel refraction.",
    );
    b.add_input::<Scene>("scene");
    b.add_input::<Camera>("camera")
        .optional()
        .doc("Overrides the scene's camera.");
    let d = WhittedSettings::default();
    b.add_input::<i64>("max_depth")
        .default(d.max_depth as i64)
        .range(1.0, 64.0)
        .doc("Longest ray tree branch in segments (camera ray = 1).");
    b.add_input::<i64>("light_samples")
        .default(d.light_samples as i64)
        .range(1.0, 4096.0)
        .doc("Stratified points per emissive triangle (rounded down to a square).");
    b.add_input::<f64>("ambient")
        .default(d.ambient as f64)
        .range(0.0, 1e3)
        .doc("Ambient radiance, added as ambient * albedo.");
    b.add_input::<i64>("aa")
        .default(d.aa as i64)
        .range(1.0, 16.0)
        .doc("Antialiasing: aa x aa rays per pixel.");
    declare_crease(b);
    b.add_output::<Image>("color").doc("Linear radiance.");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let scene: Arc<Scene> = ctx.input("scene")?;
    let camera: Option<Arc<Camera>> = ctx.input_opt("camera")?;
    let max_depth: i64 = ctx.input("max_depth")?;
    let light_samples: i64 = ctx.input("light_samples")?;
    let ambient: f64 = ctx.input("ambient")?;
    let aa: i64 = ctx.input("aa")?;
    let crease_deg = crease_input(ctx)?;
    // The declared ranges (NaN refused) are checked by the runtime on literal and linked
    // values alike.
    let s = WhittedSettings {
        max_depth: max_depth as u32,
        light_samples: light_samples as u32,
        ambient: ambient as f32,
        aa: aa as u32,
        crease_deg,
    };
    // Per pixel: the rows and the flattened image (16 bytes each).
    reserve_image(ctx, &scene, camera.as_deref(), 32)?;
    let report = ctx.progress_fn();
    let img = render_whitted(&scene, camera.as_deref(), &s, &report).map_err(trace_error)?;
    ctx.set_output("color", img);
    Ok(())
}

/// Registers `render_whitted`.
pub fn register(r: &mut Registry) {
    r.add("render_whitted", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;
    use cgnodes_api::types::{FovAxis, MaterialKind, Mesh, SceneObject};

    fn quad(z: f64, s: f64, up: bool) -> Mesh {
        let p = vec![[-s, -s, z], [s, -s, z], [s, s, z], [-s, s, z]];
        let t: &[[u32; 3]] = if up {
            &[[0, 1, 2], [0, 2, 3]]
        } else {
            &[[0, 2, 1], [0, 3, 2]]
        };
        Mesh::from_triangles(p, t).unwrap()
    }

    fn cam() -> Camera {
        Camera {
            eye: [0.0, 0.0, 5.0],
            fov_deg: 10.0,
            fov_axis: FovAxis::Smaller,
            width: 8,
            height: 8,
            far: 100.0,
            ..Default::default()
        }
    }

    /// A Lambertian plane under a point light at distance d along its normal reads
    /// albedo/pi * I / d^2 (the specular lobe is off when metallic is 0 ... up to 0.04).
    #[test]
    fn point_light_on_lambertian_plane() {
        let m = Material {
            base_color: [0.5; 3],
            metallic: 0.0,
            roughness: 1.0,
            ..Default::default()
        };
        let scene = Scene {
            objects: vec![SceneObject {
                mesh: Arc::new(quad(0.0, 10.0, true)),
                material: Some(Arc::new(m)),
            }],
            lights: vec![Light::Point {
                position: [0.0, 0.0, 2.0],
                color: [1.0; 3],
                intensity: 4.0,
            }],
            camera: Some(cam()),
        };
        let s = WhittedSettings {
            aa: 1,
            ..Default::default()
        };
        let img = render_whitted(&scene, None, &s, &|_| {}).unwrap();
        let c = img.get(4, 4)[0];
        // Diffuse 0.5/pi*1 plus the normalised Blinn-Phong lobe (s = 1 at roughness 1:
        // 0.04 * 9/(8 pi) (n.h)^1) at near-normal incidence.
        let diffuse = 0.5 * FRAC_1_PI;
        let spec = 0.04 * 9.0 / (8.0 * std::f32::consts::PI);
        let want = (diffuse + spec) * 4.0 / 4.0;
        assert!((c - want).abs() < 0.01 * want, "{c} vs {want}");
    }

    /// A mirror facing the camera shows what is behind the camera: an emitter there.
    #[test]
    fn mirror_reflects_the_emitter_and_glass_transmits_it() {
        let emitter = Material {
            base_color: [0.0; 3],
            emission: [2.0, 1.0, 0.5],
            ..Default::default()
        };
        let mirror = Material {
            kind: MaterialKind::Mirror,
            base_color: [0.5; 3],
            ..Default::default()
        };
        let scene = Scene {
            objects: vec![
                SceneObject {
                    mesh: Arc::new(quad(0.0, 10.0, true)),
                    material: Some(Arc::new(mirror)),
                },
                SceneObject {
                    mesh: Arc::new(quad(8.0, 10.0, false)),
                    material: Some(Arc::new(emitter.clone())),
                },
            ],
            camera: Some(cam()),
            ..Default::default()
        };
        let img = render_whitted(&scene, None, &WhittedSettings::default(), &|_| {}).unwrap();
        let c = img.get(4, 4);
        assert!(
            (c[0] - 1.0).abs() < 1e-4 && (c[2] - 0.25).abs() < 1e-4,
            "{c:?}"
        );
        // max_depth 1: no reflection.
        let s = WhittedSettings {
            max_depth: 1,
            ..Default::default()
        };
        let img = render_whitted(&scene, None, &s, &|_| {}).unwrap();
        assert_eq!(img.get(4, 4)[0], 0.0);
        // A glass slab between camera and emitter (behind the slab): transmittance
        // (1 - F)^2 at normal incidence with F = 0.04, ignoring inter-reflections at depth 3.
        let glass = Material {
            kind: MaterialKind::Dielectric { ior: 1.5 },
            ..Default::default()
        };
        let scene = Scene {
            objects: vec![
                SceneObject {
                    mesh: Arc::new(quad(1.0, 10.0, true)),
                    material: Some(Arc::new(glass.clone())),
                },
                SceneObject {
                    mesh: Arc::new(quad(0.5, 10.0, false)),
                    material: Some(Arc::new(glass)),
                },
                SceneObject {
                    mesh: Arc::new(quad(-1.0, 10.0, true)),
                    material: Some(Arc::new(emitter)),
                },
            ],
            camera: Some(cam()),
            ..Default::default()
        };
        let s = WhittedSettings {
            max_depth: 3,
            ..Default::default()
        };
        let img = render_whitted(&scene, None, &s, &|_| {}).unwrap();
        let c = img.get(4, 4)[0];
        let want = 2.0 * 0.96f32 * 0.96;
        assert!((c - want).abs() < 2e-3, "{c} vs {want}");
    }
}
