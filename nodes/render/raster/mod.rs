//! `render_raster`: a CPU rasterizer producing a shaded image and the deferred passes
//! (depth, normal, position, uv, base colour), as Framework3D's rasterize node gives them.
//!
//! Pipeline: the scene is flattened to world-space triangles (`geometry`); each triangle
//! is set up in 2D homogeneous coordinates and rasterized into a visibility buffer holding
//! the nearest depth and triangle per sample (`rasterize`, tiled in bands, rayon-parallel,
//! deterministic). Shading then runs per pixel: attributes are reconstructed with
//! perspective-correct barycentrics at the sample position, textures are filtered
//! trilinearly with UV derivatives taken one pixel over (`texture`), normal maps perturb
//! the normal in the tangent frame, and each light adds Blinn-Phong (`shading`) times its
//! shadow-map visibility (`shadow`).
//!
//! Anti-aliasing with `n = s^2` samples per pixel on an `s x s` grid: `ssaa` shades every
//! sample; `msaa` shades each triangle once per pixel, at the centroid of the samples it
//! covers, weighted by its coverage (the visibility-buffer form of multisampling). The
//! passes come from the nearest triangle in the pixel, evaluated at the centroid of its
//! samples; their alpha is 1 where a surface was hit and 0 elsewhere. Colour is linear
//! with alpha 1 (the background colour shows where nothing was hit).

pub mod geometry;
pub mod rasterize;
pub mod shading;
pub mod shadow;
pub mod texture;

use crate::nodes::render::camera::{camera_frame, check_camera, focal_lengths};
use crate::prelude::*;
use geometry::{scene_geometry, SceneGeometry};
use rasterize::{barycentric, rasterize, setup_triangle, TriSetup};
use rayon::prelude::*;
use shadow::{directional_shadow_map, point_shadow_map, ShadowMap, ShadowParams};
use std::sync::atomic::{AtomicU64, Ordering};
use texture::{MipTexture, Wrap};

/// Anti-aliasing mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AntiAliasing {
    /// Shade every sample.
    Supersampling,
    /// Shade each triangle once per pixel, weighted by its sample coverage.
    Multisampling,
}

/// Settings of `render`.
#[derive(Clone, Debug)]
pub struct RasterOptions {
    /// Samples per pixel along each axis (s; s^2 samples per pixel).
    pub samples_per_axis: u32,
    /// How samples are shaded.
    pub aa: AntiAliasing,
    /// Drop triangles facing away from the camera (clockwise on screen).
    pub cull_backfaces: bool,
    /// Render shadow maps.
    pub shadows: bool,
    /// Directional shadow map resolution (cube faces of point lights use half).
    pub shadow_resolution: u32,
    /// Shadow bias and PCF settings.
    pub shadow: ShadowParams,
    /// The ambient term `ka Ia` (multiplies the base colour).
    pub ambient: f64,
    /// Texture wrap mode.
    pub wrap: Wrap,
    /// Use mipmaps (trilinear filtering); otherwise bilinear on the full texture.
    pub mipmaps: bool,
    /// Colour where nothing is hit.
    pub background: [f64; 3],
}

impl Default for RasterOptions {
    fn default() -> Self {
        RasterOptions {
            samples_per_axis: 2,
            aa: AntiAliasing::Multisampling,
            cull_backfaces: false,
            shadows: true,
            shadow_resolution: 2048,
            shadow: ShadowParams {
                pcf_radius: 1,
                bias: 1.0,
                slope_bias: 1.5,
            },
            ambient: 0.2,
            wrap: Wrap::Repeat,
            mipmaps: true,
            background: [0.05, 0.05, 0.05],
        }
    }
}

/// The rendered image and passes, with counts for benchmarks.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// Shaded linear colour.
    pub color: Image,
    /// View-space depth (distance along the viewing direction) in RGB.
    pub depth: Image,
    /// World-space shading normal (after normal mapping).
    pub normal: Image,
    /// World-space position.
    pub position: Image,
    /// Texture coordinates in R and G.
    pub uv: Image,
    /// Base colour (texture times factor).
    pub base_color: Image,
    /// Triangles rasterized (after culling and clipping).
    pub triangles: usize,
    /// Shading evaluations (lit surface points).
    pub shaded: u64,
}

/// A material ready for shading.
struct MatPrep {
    base: [f64; 3],
    tex: Option<MipTexture>,
    nmap: Option<MipTexture>,
    ks: f64,
    k: f64,
    emission: [f64; 3],
}

/// A light with its shadow map.
struct LightPrep {
    light: Light,
    map: Option<ShadowMap>,
}

/// A reconstructed surface point.
struct Surf {
    p: [f64; 3],
    n: [f64; 3],
    uv: [f64; 2],
    base: [f64; 3],
    depth: f64,
    color: [f64; 3],
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn normalize(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = dot(a, a).sqrt();
    (n > 1e-300 && n.is_finite()).then(|| [a[0] / n, a[1] / n, a[2] / n])
}
fn interp3(b: [f64; 3], v: &[[f64; 3]; 3]) -> [f64; 3] {
    std::array::from_fn(|k| b[0] * v[0][k] + b[1] * v[1][k] + b[2] * v[2][k])
}
fn interp2(b: [f64; 3], v: &[[f64; 2]; 3]) -> [f64; 2] {
    std::array::from_fn(|k| b[0] * v[0][k] + b[1] * v[1][k] + b[2] * v[2][k])
}

struct Shader<'a> {
    g: &'a SceneGeometry,
    setups: &'a [Option<TriSetup>],
    mats: Vec<MatPrep>,
    lights: Vec<LightPrep>,
    eye: [f64; 3],
    forward: [f64; 3],
    opts: &'a RasterOptions,
}

impl Shader<'_> {
    /// The surface of triangle `t` seen at sample-space point `(x, y)`; texture
    /// derivatives are taken `step` samples over; `lit` evaluates the lighting.
    fn surface(&self, t: usize, x: f64, y: f64, step: f64, lit: bool) -> Option<Surf> {
        let s = self.setups[t].as_ref()?;
        let b = barycentric(&s.inv, x, y)?;
        let g = self.g;
        let pos = &g.pos[t];
        let p = interp3(b, pos);
        let v = normalize(sub(self.eye, p)).unwrap_or(self.forward.map(|c| -c));
        let mut ng = normalize(cross(sub(pos[1], pos[0]), sub(pos[2], pos[0])))?;
        let flip = dot(ng, v) < 0.0;
        if flip {
            ng = ng.map(|c| -c);
        }
        let mut n = normalize(interp3(b, &g.nrm[t])).unwrap_or(ng);
        if flip {
            n = n.map(|c| -c);
        }
        let m = &self.mats[g.mat[t] as usize];
        let uv = interp2(b, &g.uv[t]);
        let mut base = m.base;
        let has_uv = g.has_uv[t];
        let (dx, dy) = if has_uv && (m.tex.is_some() || m.nmap.is_some()) {
            let d = |bb: Option<[f64; 3]>| {
                bb.map(|bb| {
                    let w = interp2(bb, &g.uv[t]);
                    [w[0] - uv[0], w[1] - uv[1]]
                })
                .unwrap_or([0.0; 2])
            };
            (
                d(barycentric(&s.inv, x + step, y)),
                d(barycentric(&s.inv, x, y + step)),
            )
        } else {
            ([0.0; 2], [0.0; 2])
        };
        if let (true, Some(tex)) = (has_uv, &m.tex) {
            let c = tex.trilinear(uv[0], uv[1], dx, dy, self.opts.wrap);
            base = [base[0] * c[0] as f64, base[1] * c[1] as f64, base[2] * c[2] as f64];
        }
        if let (true, Some(nm)) = (has_uv, &m.nmap) {
            let tan = &g.tan[t];
            let tt = interp3(b, &[0, 1, 2].map(|k| [tan[k][0], tan[k][1], tan[k][2]]));
            let tt = sub(tt, n.map(|c| c * dot(n, tt)));
            if let Some(tt) = normalize(tt) {
                let w = if tan[0][3] < 0.0 { -1.0 } else { 1.0 };
                let bb = cross(n, tt).map(|c| c * w);
                let c = nm.trilinear(uv[0], uv[1], dx, dy, self.opts.wrap);
                let q = [0, 1, 2].map(|k| 2.0 * c[k] as f64 - 1.0);
                if let Some(nn) = normalize(std::array::from_fn(|k| {
                    q[0] * tt[k] + q[1] * bb[k] + q[2] * n[k]
                })) {
                    n = nn;
                }
            }
        }
        let mut color = [0.0; 3];
        if lit {
            for k in 0..3 {
                color[k] = self.opts.ambient * base[k] + m.emission[k];
            }
            for lp in &self.lights {
                let (l, e) = match &lp.light {
                    Light::Directional {
                        direction,
                        color,
                        intensity,
                    } => match normalize(*direction) {
                        Some(d) => (d.map(|c| -c), color.map(|c| c * intensity)),
                        None => continue,
                    },
                    Light::Point {
                        position,
                        color,
                        intensity,
                    } => {
                        let d = sub(*position, p);
                        let r2 = dot(d, d);
                        match normalize(d) {
                            Some(l) => (l, color.map(|c| c * intensity / r2)),
                            None => continue,
                        }
                    }
                };
                let f = shading::blinn_phong(n, l, v, base, m.ks, m.k);
                if f == [0.0; 3] {
                    continue;
                }
                let vis = match &lp.map {
                    Some(map) => map.visibility(p, ng, l, &self.opts.shadow),
                    None => 1.0,
                };
                for k in 0..3 {
                    color[k] += vis * e[k] * f[k];
                }
            }
        }
        Some(Surf {
            p,
            n,
            uv,
            base,
            depth: dot(sub(p, self.eye), self.forward),
            color,
        })
    }
}

/// Renders a scene through a camera (see the module doc). Fails on an unusable camera or
/// non-finite geometry.
pub fn render(scene: &Scene, cam: &Camera, opts: &RasterOptions) -> Result<RenderOutput, String> {
    check_camera(cam)?;
    let s = opts.samples_per_axis.clamp(1, 8);
    let (w, h) = (cam.width, cam.height);
    let (ws, hs) = (w * s, h * s);
    let g = scene_geometry(scene)?;
    let [right, up, fwd] = camera_frame(cam)?;
    let (fx, _) = focal_lengths(cam);
    let f = fx * s as f64;
    let (cx, cy) = (ws as f64 * 0.5, hs as f64 * 0.5);
    let eye = cam.eye;
    let setups: Vec<Option<TriSetup>> = g
        .pos
        .par_iter()
        .map(|t| {
            let c = t.map(|p| {
                let d = sub(p, eye);
                [dot(d, right), dot(d, up), dot(d, fwd)]
            });
            if c.iter().all(|v| v[2] < cam.near) || c.iter().all(|v| v[2] > cam.far) {
                return None;
            }
            let hh = c.map(|v| [cx * v[2] + f * v[0], cy * v[2] - f * v[1], v[2]]);
            let st = setup_triangle(hh, c.map(|v| v[2]), cam.near, ws, hs)?;
            // det M < 0 is counter-clockwise seen from the eye (the camera frame is
            // left-handed and the pixel y axis points down: two sign flips and f^2 > 0).
            if opts.cull_backfaces && !st.det_negative {
                return None;
            }
            Some(st)
        })
        .collect();
    let triangles = setups.iter().filter(|t| t.is_some()).count();
    let vis = rasterize(&setups, ws, hs, cam.near, cam.far, true);

    let mats = g
        .materials
        .iter()
        .map(|m| MatPrep {
            base: m.base_color,
            tex: m.base_color_texture.as_ref().map(|t| MipTexture::new(t, opts.mipmaps)),
            nmap: m.normal_map.as_ref().map(|t| MipTexture::new(t, opts.mipmaps)),
            ks: shading::specular_weight(m.metallic),
            k: shading::roughness_to_exponent(m.roughness),
            emission: m.emission,
        })
        .collect();
    let res = opts.shadow_resolution.clamp(16, 8192);
    let diag = dot(sub(g.bounds.1, g.bounds.0), sub(g.bounds.1, g.bounds.0)).sqrt();
    let lights = scene
        .lights
        .iter()
        .map(|l| LightPrep {
            light: l.clone(),
            map: (opts.shadows && !g.pos.is_empty()).then(|| match l {
                Light::Directional { direction, .. } => {
                    directional_shadow_map(&g.pos, *direction, g.bounds, res)
                }
                Light::Point { position, .. } => {
                    point_shadow_map(&g.pos, *position, (res / 2).max(16), (1e-5 * diag).max(1e-9))
                }
            }),
        })
        .collect();
    let sh = Shader {
        g: &g,
        setups: &setups,
        mats,
        lights,
        eye,
        forward: fwd,
        opts,
    };

    let npx = w as usize * h as usize;
    let zero = [0.0f32; 4];
    let bg = [
        opts.background[0] as f32,
        opts.background[1] as f32,
        opts.background[2] as f32,
        1.0,
    ];
    let mut color = vec![bg; npx];
    let mut depth = vec![zero; npx];
    let mut normal = vec![zero; npx];
    let mut position = vec![zero; npx];
    let mut uvp = vec![zero; npx];
    let mut basep = vec![zero; npx];
    let shaded = AtomicU64::new(0);
    let wu = w as usize;
    let n_samples = (s * s) as f64;
    color
        .par_chunks_mut(wu)
        .zip(depth.par_chunks_mut(wu))
        .zip(normal.par_chunks_mut(wu))
        .zip(position.par_chunks_mut(wu))
        .zip(uvp.par_chunks_mut(wu))
        .zip(basep.par_chunks_mut(wu))
        .enumerate()
        .for_each(|(py, (((((crow, drow), nrow), prow), urow), brow))| {
            let mut count = 0u64;
            // (triangle, covered samples, sum of sample x, sum of sample y, min depth)
            let mut groups: Vec<(u32, u32, f64, f64, f32)> = Vec::with_capacity(16);
            for px in 0..wu {
                groups.clear();
                let mut acc = [0.0f64; 3];
                let mut empty = 0u32;
                for j in 0..s as usize {
                    let sy = py * s as usize + j;
                    for i in 0..s as usize {
                        let sx = px * s as usize + i;
                        let k = sy * ws as usize + sx;
                        let id = vis.ids[k];
                        if id == u32::MAX {
                            empty += 1;
                            continue;
                        }
                        let (xc, yc) = (sx as f64 + 0.5, sy as f64 + 0.5);
                        if opts.aa == AntiAliasing::Supersampling {
                            if let Some(sf) = sh.surface(id as usize, xc, yc, 1.0, true) {
                                count += 1;
                                for c in 0..3 {
                                    acc[c] += sf.color[c];
                                }
                            }
                        }
                        let d = vis.depth[k];
                        match groups.iter_mut().find(|g| g.0 == id) {
                            Some(g) => {
                                g.1 += 1;
                                g.2 += xc;
                                g.3 += yc;
                                g.4 = g.4.min(d);
                            }
                            None => groups.push((id, 1, xc, yc, d)),
                        }
                    }
                }
                if groups.is_empty() {
                    continue;
                }
                // The nearest triangle in the pixel (first on ties) gives the passes.
                let mut nearest = 0;
                for (gi, gr) in groups.iter().enumerate() {
                    if gr.4 < groups[nearest].4 {
                        nearest = gi;
                    }
                }
                let step = s as f64;
                let mut pass_surf = None;
                for (gi, gr) in groups.iter().enumerate() {
                    let (x, y) = (gr.2 / gr.1 as f64, gr.3 / gr.1 as f64);
                    if opts.aa == AntiAliasing::Multisampling {
                        if let Some(sf) = sh.surface(gr.0 as usize, x, y, step, true) {
                            count += 1;
                            for c in 0..3 {
                                acc[c] += sf.color[c] * gr.1 as f64;
                            }
                            if gi == nearest {
                                pass_surf = Some(sf);
                            }
                        }
                    } else if gi == nearest {
                        pass_surf = sh.surface(gr.0 as usize, x, y, step, false);
                    }
                }
                for c in 0..3 {
                    acc[c] += opts.background[c] * empty as f64;
                }
                crow[px] = [
                    (acc[0] / n_samples) as f32,
                    (acc[1] / n_samples) as f32,
                    (acc[2] / n_samples) as f32,
                    1.0,
                ];
                if let Some(sf) = pass_surf {
                    let d = sf.depth as f32;
                    drow[px] = [d, d, d, 1.0];
                    nrow[px] = [sf.n[0] as f32, sf.n[1] as f32, sf.n[2] as f32, 1.0];
                    prow[px] = [sf.p[0] as f32, sf.p[1] as f32, sf.p[2] as f32, 1.0];
                    urow[px] = [sf.uv[0] as f32, sf.uv[1] as f32, 0.0, 1.0];
                    brow[px] = [sf.base[0] as f32, sf.base[1] as f32, sf.base[2] as f32, 1.0];
                }
            }
            shaded.fetch_add(count, Ordering::Relaxed);
        });
    let img = |pixels| Image {
        width: w,
        height: h,
        pixels,
    };
    Ok(RenderOutput {
        color: img(color),
        depth: img(depth),
        normal: img(normal),
        position: img(position),
        uv: img(uvp),
        base_color: img(basep),
        triangles,
        shaded: shaded.into_inner(),
    })
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Rasterizes a scene: Blinn-Phong with shadow maps, textures and normal maps, plus deferred passes.")
        .category("render");
    b.add_input::<Scene>("scene").doc("Meshes, materials, lights and usually the camera.");
    b.add_input::<Camera>("camera")
        .optional()
        .doc("Camera; overrides the scene's camera.");
    b.add_input::<String>("antialiasing")
        .choices(&["msaa", "ssaa"])
        .doc("msaa shades each triangle once per pixel; ssaa shades every sample.");
    b.add_input::<i64>("samples")
        .default(4i64)
        .range(1.0, 64.0)
        .doc("Samples per pixel: a square, 1, 4, 9, 16, ...");
    b.add_input::<bool>("cull_backfaces")
        .default(false)
        .doc("Skip triangles seen from behind (clockwise on screen).");
    b.add_input::<bool>("shadows").default(true).doc("Render shadow maps.");
    b.add_input::<i64>("shadow_resolution")
        .default(2048i64)
        .range(256.0, 8192.0)
        .doc("Shadow map size; point-light cube faces use half of it.");
    b.add_input::<i64>("pcf_radius")
        .default(1i64)
        .range(0.0, 4.0)
        .doc("Percentage-closer filtering radius r: (2r+1)^2 taps.");
    b.add_input::<f64>("shadow_bias")
        .default(1.0)
        .range(0.0, 100.0)
        .doc("Constant depth bias, in shadow-map texels.");
    b.add_input::<f64>("shadow_slope_bias")
        .default(1.5)
        .range(0.0, 100.0)
        .doc("Slope-scaled depth bias, in texels per unit tan(angle) and PCF ring.");
    b.add_input::<f64>("ambient")
        .default(0.2)
        .range(0.0, 10.0)
        .doc("Ambient term ka*Ia, times the base colour.");
    b.add_input::<String>("texture_wrap")
        .choices(&["repeat", "clamp", "mirror"])
        .doc("What textures do outside UV 0..1.");
    b.add_input::<bool>("mipmaps")
        .default(true)
        .doc("Trilinear filtering through a mipmap pyramid (else bilinear).");
    b.add_input::<Color>("background")
        .default(Color([0.05, 0.05, 0.05]))
        .doc("Colour where nothing is hit.");
    b.add_output::<Image>("color").doc("Shaded linear colour.");
    b.add_output::<Image>("depth").doc("View depth along the viewing direction.");
    b.add_output::<Image>("normal").doc("World-space shading normal.");
    b.add_output::<Image>("position").doc("World-space position.");
    b.add_output::<Image>("uv").doc("Texture coordinates (R, G).");
    b.add_output::<Image>("base_color").doc("Base colour (texture times factor).");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let scene: Arc<Scene> = ctx.input("scene")?;
    let cam: Option<Arc<Camera>> = ctx.input_opt("camera")?;
    let cam = match (cam, &scene.camera) {
        (Some(c), _) => (*c).clone(),
        (None, Some(c)) => c.clone(),
        (None, None) => {
            return Err(NodeError::invalid(
                "camera",
                "the scene has no camera; connect one to 'camera' or to the scene node",
            ))
        }
    };
    let samples: i64 = ctx.input("samples")?;
    let sa = (samples.max(1) as f64).sqrt().round() as i64;
    if sa * sa != samples || !(1..=8).contains(&sa) {
        return Err(NodeError::invalid(
            "samples",
            format!("{samples} is not a square number of samples in 1..=64"),
        ));
    }
    let aa: String = ctx.input("antialiasing")?;
    let res: i64 = ctx.input("shadow_resolution")?;
    if !(256..=8192).contains(&res) {
        return Err(NodeError::invalid("shadow_resolution", "must lie in 256..=8192"));
    }
    let pcf: i64 = ctx.input("pcf_radius")?;
    if !(0..=4).contains(&pcf) {
        return Err(NodeError::invalid("pcf_radius", "must lie in 0..=4"));
    }
    let bias: f64 = ctx.input("shadow_bias")?;
    let slope: f64 = ctx.input("shadow_slope_bias")?;
    let ambient: f64 = ctx.input("ambient")?;
    for (n, v) in [("shadow_bias", bias), ("shadow_slope_bias", slope), ("ambient", ambient)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(NodeError::invalid(n, "must be finite and not negative"));
        }
    }
    let wrap: String = ctx.input("texture_wrap")?;
    let bgc: Color = ctx.input("background")?;
    let opts = RasterOptions {
        samples_per_axis: sa as u32,
        aa: if aa == "ssaa" {
            AntiAliasing::Supersampling
        } else {
            AntiAliasing::Multisampling
        },
        cull_backfaces: ctx.input("cull_backfaces")?,
        shadows: ctx.input("shadows")?,
        shadow_resolution: res as u32,
        shadow: ShadowParams {
            pcf_radius: pcf as u32,
            bias,
            slope_bias: slope,
        },
        ambient,
        wrap: match wrap.as_str() {
            "clamp" => Wrap::Clamp,
            "mirror" => Wrap::Mirror,
            _ => Wrap::Repeat,
        },
        mipmaps: ctx.input("mipmaps")?,
        background: bgc.0,
    };
    let out = render(&scene, &cam, &opts).map_err(|e| NodeError::invalid("scene", e))?;
    ctx.log(format!(
        "{}x{} with {} samples: {} triangles, {} shading evaluations",
        cam.width, cam.height, samples, out.triangles, out.shaded
    ));
    ctx.set_output("color", out.color);
    ctx.set_output("depth", out.depth);
    ctx.set_output("normal", out.normal);
    ctx.set_output("position", out.position);
    ctx.set_output("uv", out.uv);
    ctx.set_output("base_color", out.base_color);
    Ok(())
}

/// Registers `render_raster`.
pub fn register(r: &mut Registry) {
    r.add("render_raster", declare, execute);
}
