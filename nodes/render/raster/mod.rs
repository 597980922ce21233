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
use crate::types::vec3::{cross, dot, sub};
use geometry::{scene_geometry, SceneGeometry};
use rasterize::{barycentric, bin_rows, fill_rows, setup_triangle, TriSetup};
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
    /// The images to produce (default all).
    pub passes: Passes,
}

/// Which images `render` produces. A pass left out comes back as an empty (0 x 0) image
/// and costs neither memory nor time; without `color` nothing is lit (no shadow maps).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Passes {
    /// Shaded colour.
    pub color: bool,
    /// View depth.
    pub depth: bool,
    /// World-space normal.
    pub normal: bool,
    /// World-space position.
    pub position: bool,
    /// Texture coordinates.
    pub uv: bool,
    /// Base colour.
    pub base_color: bool,
}

impl Passes {
    /// Every pass.
    pub const ALL: Passes = Passes {
        color: true,
        depth: true,
        normal: true,
        position: true,
        uv: true,
        base_color: true,
    };
    /// The shaded colour only.
    pub const COLOR: Passes = Passes {
        color: true,
        depth: false,
        normal: false,
        position: false,
        uv: false,
        base_color: false,
    };
    /// No pass (a base for struct update: `Passes { depth: true, ..Passes::NONE }`).
    pub const NONE: Passes = Passes {
        color: false,
        depth: false,
        normal: false,
        position: false,
        uv: false,
        base_color: false,
    };
    /// Whether any pass other than colour is on.
    fn any_surface(&self) -> bool {
        self.depth || self.normal || self.position || self.uv || self.base_color
    }
}

impl Default for Passes {
    fn default() -> Self {
        Passes::ALL
    }
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
            passes: Passes::ALL,
        }
    }
}

/// The rendered image and passes, with counts for benchmarks. Passes not asked for in
/// `RasterOptions::passes` are empty (0 x 0) images.
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
    /// A directional light's unit direction towards it and irradiance, computed once.
    dir: Option<([f64; 3], [f64; 3])>,
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

fn normalize(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = dot(a, a).sqrt();
    // One division and three products: shading normalizes several vectors per sample.
    (n > 1e-300 && n.is_finite()).then(|| {
        let r = 1.0 / n;
        [a[0] * r, a[1] * r, a[2] * r]
    })
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
    /// Unit geometric normal of each rasterized triangle (`None` when degenerate).
    ngs: &'a [Option<[f64; 3]>],
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
        let mut ng = self.ngs[t]?;
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
            base = [
                base[0] * c[0] as f64,
                base[1] * c[1] as f64,
                base[2] * c[2] as f64,
            ];
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
                    Light::Directional { .. } => match lp.dir {
                        Some(le) => le,
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
/// non-finite geometry. Only the passes in `opts.passes` are produced.
pub fn render(scene: &Scene, cam: &Camera, opts: &RasterOptions) -> Result<RenderOutput, String> {
    check_camera(cam)?;
    let s = opts.samples_per_axis.clamp(1, 8);
    let (w, h) = (cam.width, cam.height);
    let (ws, hs) = (w * s, h * s);
    let passes = opts.passes;
    let lit = passes.color;
    let g = scene_geometry(scene)?;
    let [right, up, fwd] = camera_frame(cam)?;
    let (fx, _) = focal_lengths(cam);
    let f = fx * s as f64;
    let (cx, cy) = (ws as f64 * 0.5, hs as f64 * 0.5);
    let eye = cam.eye;
    // Pixel rows per band: each band is rasterized into a small sample buffer and shaded
    // right away (fused, so the full-resolution sample buffer never exists).
    const BAND_PX: usize = 8;
    let band_rows = BAND_PX as u32 * s;
    let res = opts.shadow_resolution.clamp(16, 8192);
    let diag = dot(sub(g.bounds.1, g.bounds.0), sub(g.bounds.1, g.bounds.0)).sqrt();
    // The camera's triangle setup and the shadow maps (one light per task) are
    // independent: build them side by side.
    let camera_setup = || {
        let (setups, ngs): (Vec<Option<TriSetup>>, Vec<Option<[f64; 3]>>) = g
            .pos
            .par_iter()
            .map(|t| {
                let c = t.map(|p| {
                    let d = sub(p, eye);
                    [dot(d, right), dot(d, up), dot(d, fwd)]
                });
                if c.iter().all(|v| v[2] < cam.near) || c.iter().all(|v| v[2] > cam.far) {
                    return (None, None);
                }
                let hh = c.map(|v| [cx * v[2] + f * v[0], cy * v[2] - f * v[1], v[2]]);
                let Some(st) = setup_triangle(hh, c.map(|v| v[2]), cam.near, ws, hs) else {
                    return (None, None);
                };
                // det M < 0 is counter-clockwise seen from the eye (the camera frame is
                // left-handed and the pixel y axis points down: two sign flips and f^2 > 0).
                if opts.cull_backfaces && !st.det_negative {
                    return (None, None);
                }
                let ng = normalize(cross(sub(t[1], t[0]), sub(t[2], t[0])));
                (Some(st), ng)
            })
            .unzip();
        let bins = bin_rows(&setups, hs, band_rows);
        (setups, ngs, bins)
    };
    let light_preps = || {
        scene
            .lights
            .par_iter()
            .map(|l| LightPrep {
                light: l.clone(),
                dir: match l {
                    Light::Directional {
                        direction,
                        color,
                        intensity,
                    } => {
                        normalize(*direction).map(|d| (d.map(|c| -c), color.map(|c| c * intensity)))
                    }
                    Light::Point { .. } => None,
                },
                map: (lit && opts.shadows && !g.pos.is_empty()).then(|| match l {
                    Light::Directional { direction, .. } => {
                        directional_shadow_map(&g.pos, *direction, g.bounds, res)
                    }
                    Light::Point { position, .. } => point_shadow_map(
                        &g.pos,
                        *position,
                        (res / 2).max(16),
                        (1e-5 * diag).max(1e-9),
                    ),
                }),
            })
            .collect::<Vec<_>>()
    };
    let ((setups, ngs, bins), lights) = rayon::join(camera_setup, light_preps);
    let triangles = setups.iter().filter(|t| t.is_some()).count();

    let mats = g
        .materials
        .iter()
        .map(|m| MatPrep {
            base: m.base_color,
            tex: m
                .base_color_texture
                .as_ref()
                .map(|t| MipTexture::new(t, opts.mipmaps)),
            nmap: m
                .normal_map
                .as_ref()
                .map(|t| MipTexture::new(t, opts.mipmaps)),
            ks: shading::specular_weight(m.metallic),
            k: shading::roughness_to_exponent(m.roughness),
            emission: m.emission,
        })
        .collect();
    let sh = Shader {
        g: &g,
        setups: &setups,
        ngs: &ngs,
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
    // Only the passes asked for get a buffer.
    let alloc = |on: bool, v: [f32; 4]| if on { vec![v; npx] } else { Vec::new() };
    let mut color = alloc(passes.color, bg);
    let mut depth = alloc(passes.depth, zero);
    let mut normal = alloc(passes.normal, zero);
    let mut position = alloc(passes.position, zero);
    let mut uvp = alloc(passes.uv, zero);
    let mut basep = alloc(passes.base_color, zero);
    let shaded = AtomicU64::new(0);
    let wu = w as usize;
    let n_samples = (s * s) as f64;
    let band_len = wu * BAND_PX;
    let band_samples = ws as usize * band_rows as usize;
    let nbands = bins.len();
    type Px = [f32; 4];
    // Each band's slice of every produced pass (`None` for passes not produced).
    let surface_passes = passes.any_surface();
    if lit || surface_passes {
        let mut chunks: Vec<std::vec::IntoIter<Option<&mut [Px]>>> = [
            &mut color,
            &mut depth,
            &mut normal,
            &mut position,
            &mut uvp,
            &mut basep,
        ]
        .into_iter()
        .map(|buf| {
            let v: Vec<Option<&mut [Px]>> = if buf.is_empty() {
                (0..nbands).map(|_| None).collect()
            } else {
                buf.chunks_mut(band_len).map(Some).collect()
            };
            v.into_iter()
        })
        .collect();
        let bands: Vec<[Option<&mut [Px]>; 6]> = (0..nbands)
            .map(|_| std::array::from_fn(|k| chunks[k].next().flatten()))
            .collect();
        bands.into_par_iter().enumerate().for_each_init(
            || {
                // (triangle, covered samples, sum of sample x, sum of sample y, min depth)
                let groups: Vec<(u32, u32, f64, f64, f32)> = Vec::with_capacity(16);
                (Vec::new(), Vec::new(), groups)
            },
            |(zbuf, ibuf, groups), (bi, mut out)| {
                zbuf.clear();
                zbuf.resize(band_samples, f32::INFINITY);
                ibuf.clear();
                ibuf.resize(band_samples, u32::MAX);
                let y_start = bi as u32 * band_rows;
                let y_end = (y_start + band_rows).min(hs);
                fill_rows(
                    &setups,
                    &bins[bi],
                    y_start,
                    y_end,
                    ws,
                    cam.near,
                    cam.far,
                    zbuf,
                    Some(ibuf),
                );
                let mut count = 0u64;
                let rows = (y_end - y_start) as usize / s as usize;
                for r in 0..rows {
                    let py = bi * BAND_PX + r;
                    for px in 0..wu {
                        groups.clear();
                        let mut acc = [0.0f64; 3];
                        let mut empty = 0u32;
                        for j in 0..s as usize {
                            let sy = py * s as usize + j;
                            for i in 0..s as usize {
                                let sx = px * s as usize + i;
                                let k = (sy - y_start as usize) * ws as usize + sx;
                                let id = ibuf[k];
                                if id == u32::MAX {
                                    empty += 1;
                                    continue;
                                }
                                let (xc, yc) = (sx as f64 + 0.5, sy as f64 + 0.5);
                                if lit && opts.aa == AntiAliasing::Supersampling {
                                    if let Some(sf) = sh.surface(id as usize, xc, yc, 1.0, true) {
                                        count += 1;
                                        for (a, c) in acc.iter_mut().zip(sf.color) {
                                            *a += c;
                                        }
                                    }
                                }
                                let d = zbuf[k];
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
                            if lit && opts.aa == AntiAliasing::Multisampling {
                                if let Some(sf) = sh.surface(gr.0 as usize, x, y, step, true) {
                                    count += 1;
                                    for (a, c) in acc.iter_mut().zip(sf.color) {
                                        *a += c * gr.1 as f64;
                                    }
                                    if gi == nearest {
                                        pass_surf = Some(sf);
                                    }
                                }
                            } else if gi == nearest && surface_passes {
                                pass_surf = sh.surface(gr.0 as usize, x, y, step, false);
                            }
                        }
                        let o = r * wu + px;
                        if let Some(c) = out[0].as_deref_mut() {
                            for (a, c) in acc.iter_mut().zip(opts.background) {
                                *a += c * empty as f64;
                            }
                            c[o] = [
                                (acc[0] / n_samples) as f32,
                                (acc[1] / n_samples) as f32,
                                (acc[2] / n_samples) as f32,
                                1.0,
                            ];
                        }
                        let Some(sf) = pass_surf else {
                            continue;
                        };
                        let f3 = |v: [f64; 3]| [v[0] as f32, v[1] as f32, v[2] as f32, 1.0];
                        let d = sf.depth as f32;
                        let vals = [
                            [d, d, d, 1.0],
                            f3(sf.n),
                            f3(sf.p),
                            [sf.uv[0] as f32, sf.uv[1] as f32, 0.0, 1.0],
                            f3(sf.base),
                        ];
                        for (band, v) in out[1..].iter_mut().zip(vals) {
                            if let Some(b) = band.as_deref_mut() {
                                b[o] = v;
                            }
                        }
                    }
                }
                shaded.fetch_add(count, Ordering::Relaxed);
            },
        );
    }
    let img = |pixels: Vec<Px>| {
        if pixels.is_empty() {
            Image {
                width: 0,
                height: 0,
                pixels,
            }
        } else {
            Image {
                width: w,
                height: h,
                pixels,
            }
        }
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
    b.add_input::<Scene>("scene")
        .doc("Meshes, materials, lights and usually the camera.");
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
    b.add_input::<bool>("shadows")
        .default(true)
        .doc("Render shadow maps.");
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
    b.add_output::<Image>("depth")
        .doc("View depth along the viewing direction.");
    b.add_output::<Image>("normal")
        .doc("World-space shading normal.");
    b.add_output::<Image>("position")
        .doc("World-space position.");
    b.add_output::<Image>("uv")
        .doc("Texture coordinates (R, G).");
    b.add_output::<Image>("base_color")
        .doc("Base colour (texture times factor).");
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
        return Err(NodeError::invalid(
            "shadow_resolution",
            "must lie in 256..=8192",
        ));
    }
    let pcf: i64 = ctx.input("pcf_radius")?;
    if !(0..=4).contains(&pcf) {
        return Err(NodeError::invalid("pcf_radius", "must lie in 0..=4"));
    }
    let bias: f64 = ctx.input("shadow_bias")?;
    let slope: f64 = ctx.input("shadow_slope_bias")?;
    let ambient: f64 = ctx.input("ambient")?;
    for (n, v) in [
        ("shadow_bias", bias),
        ("shadow_slope_bias", slope),
        ("ambient", ambient),
    ] {
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
        // Only the passes someone reads are computed (and allocated).
        passes: Passes {
            color: ctx.output_wanted("color"),
            depth: ctx.output_wanted("depth"),
            normal: ctx.output_wanted("normal"),
            position: ctx.output_wanted("position"),
            uv: ctx.output_wanted("uv"),
            base_color: ctx.output_wanted("base_color"),
        },
    };
    let out = render(&scene, &cam, &opts).map_err(|e| NodeError::invalid("scene", e))?;
    ctx.log(format!(
        "{}x{} with {} samples: {} triangles, {} shading evaluations",
        cam.width, cam.height, samples, out.triangles, out.shaded
    ));
    for (name, on, img) in [
        ("color", opts.passes.color, out.color),
        ("depth", opts.passes.depth, out.depth),
        ("normal", opts.passes.normal, out.normal),
        ("position", opts.passes.position, out.position),
        ("uv", opts.passes.uv, out.uv),
        ("base_color", opts.passes.base_color, out.base_color),
    ] {
        if on {
            ctx.set_output(name, img);
        }
    }
    Ok(())
}

/// Registers `render_raster`.
pub fn register(r: &mut Registry) {
    r.add("render_raster", declare, execute);
}
