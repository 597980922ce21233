//! `render_path`: unidirectional path tracing (Kajiya 1986) with next-event estimation on
//! area emitters, BSDF importance sampling, multiple importance sampling with the power
//! heuristic (Veach & Guibas 1995; Veach 1997, ch. 9), and Russian roulette.
//!
//! Depth counting follows Mitsuba 3's `path` integrator, so results compare one to one:
//! `max_depth` counts path segments (vertices after the eye), so `max_depth = 1` shows only
//! emitters seen directly, 2 adds direct lighting, and the default 8 allows at most 7
//! bounces; energy carried by longer paths is lost. Russian roulette starts once `rr_depth`
//! bounces have been sampled, with survival probability min(max(throughput) eta^2, 0.95).
//!
//! Each pixel sample draws its random numbers from its own PCG32 stream seeded by a hash of
//! (pixel, sample index, seed), so images are identical whatever the thread count. Tiles of
//! 16x16 pixels render in parallel with rayon. The reconstruction filter is a box (the plain
//! per-pixel average) or Mitsuba's Gaussian (stddev 0.5 px, radius 2 px), whose samples are
//! splatted into the neighbouring pixels and normalised by the summed filter weights.

use super::direct::{delta_lights, environment_nee, Vertex};
use super::bvh::{Segment, TraceStacks};
use super::path_lanes::{self, Job, Sample};
use super::render_scene::{prepare, PinholeCamera, RenderScene};
use super::sampling::{add, dot, max_comp, mul, power_heuristic, scale, sub, Pcg32, V3};
use super::tracer_node::{crease_input, declare_crease, reserve_image, trace_error};
use crate::prelude::*;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Which sampling strategies the estimator combines (MIS is the default; the others are
/// for teaching and for checking that all three agree in expectation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// Emitter and BSDF sampling weighted by the power heuristic.
    Mis,
    /// Emitter sampling only (emitters hit by BSDF-sampled rays after a non-delta bounce
    /// count zero).
    Nee,
    /// BSDF sampling only (no shadow rays to area emitters).
    Bsdf,
}

/// The pixel reconstruction filter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    /// One pixel wide: the plain average of the pixel's samples.
    Box,
    /// Mitsuba's `gaussian`: stddev 0.5 px truncated at radius 2 px, splatted.
    Gaussian,
}

impl Choice for Strategy {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("mis", Strategy::Mis),
        ("nee", Strategy::Nee),
        ("bsdf", Strategy::Bsdf),
    ];
}

impl Choice for Filter {
    const CHOICES: &'static [(&'static str, Self)] =
        &[("gaussian", Filter::Gaussian), ("box", Filter::Box)];
}

/// Path tracer settings.
#[derive(Clone, Debug)]
pub struct PathSettings {
    /// Samples per pixel.
    pub spp: u32,
    /// Longest path in segments (Mitsuba's meaning; `u32::MAX` for unbounded).
    pub max_depth: u32,
    /// Bounces before Russian roulette starts.
    pub rr_depth: u32,
    /// Seed of the per-sample random streams.
    pub seed: u64,
    /// Reconstruction filter.
    pub filter: Filter,
    /// Sampling strategies.
    pub strategy: Strategy,
    /// Crease angle in degrees for computed vertex normals (0 = flat shading).
    pub crease_deg: f64,
}

impl Default for PathSettings {
    fn default() -> Self {
        PathSettings {
            spp: 16,
            max_depth: 8,
            rr_depth: 5,
            seed: 0,
            filter: Filter::Gaussian,
            strategy: Strategy::Mis,
            crease_deg: super::render_scene::DEFAULT_CREASE_DEG,
        }
    }
}

/// Direct light estimated at a path vertex whose shadow ray has not been traced yet: it is
/// traced together with the next segment's ray (`Bvh::intersect_occluded`, two
/// independent traversals interleaved) and added to the path's radiance before anything
/// the next segment finds, in the order the estimates were made, so the sums are bit for
/// bit those of tracing the shadow ray at once.
struct Deferred {
    /// The area emitter sample's shadow ray and its contribution when unblocked.
    nee: Option<(Segment, V3)>,
    /// Point and directional lights (their shadow rays already traced).
    delta: V3,
    /// The environment sample, when one was drawn.
    env: Option<V3>,
}

impl Deferred {
    /// Adds the estimates to `l`, the emitter sample's only when `blocked` is false.
    #[inline]
    fn add_to(&self, l: V3, blocked: bool) -> V3 {
        let mut l = l;
        if let (Some((_, c)), false) = (self.nee, blocked) {
            l = add(l, c);
        }
        l = add(l, self.delta);
        if let Some(e) = self.env {
            l = add(l, e);
        }
        l
    }

    /// Traces the shadow ray alone (the path ends here) and adds the estimates to `l`.
    #[inline]
    fn finish(&self, sc: &RenderScene, l: V3) -> V3 {
        let blocked = self.nee.is_some_and(|((o, d, t), _)| sc.bvh.occluded(o, d, t));
        self.add_to(l, blocked)
    }
}

/// The weight of radiance that a BSDF-sampled ray found on an emitter or in the environment
/// (Veach 1997, eq. 9.13): 1 for the camera ray and after a delta bounce (`first`), else
/// by strategy; `light_pdf` gives the solid-angle density with which light sampling would
/// have chosen the same direction.
#[inline(always)]
pub(crate) fn found_weight(
    strategy: Strategy,
    first: bool,
    prev_pdf: f32,
    light_pdf: impl FnOnce() -> f32,
) -> f32 {
    if first {
        return 1.0;
    }
    match strategy {
        Strategy::Bsdf => 1.0,
        Strategy::Nee => 0.0,
        Strategy::Mis => power_heuristic(prev_pdf, light_pdf()),
    }
}

/// Radiance arriving at `org` from direction `-dir` (unit `dir`), estimated with one path.
/// `stacks` are the traversal stacks the path's rays use (one set per thread, reused).
pub fn radiance(
    sc: &RenderScene,
    org: V3,
    dir: V3,
    tmax: f32,
    rng: &mut Pcg32,
    s: &PathSettings,
    stacks: &mut TraceStacks,
) -> V3 {
    let mut l = [0.0f32; 3];
    let mut thr = [1.0f32; 3];
    let mut eta = 1.0f32;
    let mut prev_pdf = 0.0f32;
    let mut prev_delta = true;
    let mut depth = 0u32;
    let (mut org, mut dir, mut tmax) = (org, dir, tmax);
    // The previous vertex's direct light, waiting for its shadow ray.
    let mut pending: Option<Deferred> = None;
    loop {
        let hit = match pending.take() {
            None => sc.intersect(org, dir, tmax),
            Some(d) => {
                let (hit, blocked) = match d.nee {
                    Some((shadow, _)) => {
                        sc.bvh
                            .intersect_occluded_in(stacks, (org, dir, tmax), shadow)
                    }
                    None => (sc.intersect(org, dir, tmax), false),
                };
                l = d.add_to(l, blocked);
                hit
            }
        };
        let Some(hit) = hit else {
            // The ray escapes: the environment's radiance, weighted like an emitter hit.
            if let Some(env) = &sc.env {
                let first = depth == 0 || prev_delta;
                let w = found_weight(s.strategy, first, prev_pdf, || env.pdf(dir));
                l = add(l, scale(mul(thr, env.eval(dir)), w));
            }
            break;
        };
        let tri = hit.prim;
        let ng = sc.normals[tri as usize];
        let mat = sc.material(tri);
        let wo = scale(dir, -1.0);
        let p = add(org, scale(dir, hit.t));

        // Emission found by the ray just traced (Veach 1997, eq. 9.13 for the weight).
        if mat.is_emitter() {
            let le = sc.emitted(tri, wo);
            if max_comp(le) > 0.0 {
                let first = depth == 0 || prev_delta;
                let w = found_weight(s.strategy, first, prev_pdf, || {
                    let cos_l = dot(ng, wo).abs();
                    sc.light_pdf_area[tri as usize] * hit.t * hit.t / cos_l
                });
                l = add(l, scale(mul(thr, le), w));
            }
        }
        if depth + 1 >= s.max_depth {
            break;
        }
        let bsdf = mat.bsdf;
        let sp = sc.surface(&hit);
        let (ns, albedo) = (sp.ns, sp.albedo);
        if !bsdf.is_delta() {
            let mut d = Deferred {
                nee: None,
                delta: [0.0; 3],
                env: None,
            };
            // Next-event estimation on the area emitters.
            if s.strategy != Strategy::Bsdf {
                let u = rng.next_f32();
                let uv = rng.next_2d();
                if let Some(ls) = sc.sample_emitter(u, uv) {
                    let dv = sub(ls.p, p);
                    let dist2 = dot(dv, dv);
                    let dist = dist2.sqrt();
                    if dist > 0.0 {
                        let wi = scale(dv, 1.0 / dist);
                        let le = sc.emitted(ls.tri, scale(wi, -1.0));
                        let cos_l = dot(ls.n, wi).abs();
                        if max_comp(le) > 0.0 && cos_l > 0.0 {
                            let (f, bsdf_pdf) = bsdf.eval_pdf(albedo, ng, ns, wo, wi);
                            if max_comp(f) > 0.0 {
                                let side = if dot(ng, wi) > 0.0 {
                                    ng
                                } else {
                                    scale(ng, -1.0)
                                };
                                let o = sc.offset(p, side);
                                let p_light = ls.pdf_area * dist2 / cos_l;
                                let w = if s.strategy == Strategy::Mis {
                                    power_heuristic(p_light, bsdf_pdf)
                                } else {
                                    1.0
                                };
                                let c = scale(mul(thr, mul(f, le)), w / p_light);
                                d.nee = Some(((o, sub(ls.p, o), 1.0 - 1e-4), c));
                            }
                        }
                    }
                }
            }
            // Point and directional lights (delta lights: only shadow rays reach them),
            // and one environment sample.
            let v = Vertex {
                p,
                wo,
                sp: &sp,
                bsdf,
            };
            if !sc.lights.is_empty() {
                d.delta = mul(thr, delta_lights(sc, &v));
            }
            if sc.env.is_some() && s.strategy != Strategy::Bsdf {
                let u = rng.next_2d();
                let le = environment_nee(sc, &v, u, s.strategy == Strategy::Mis);
                d.env = Some(mul(thr, le));
            }
            pending = Some(d);
        }
        // BSDF sampling for the next segment.
        let u = rng.next_f32();
        let uv = rng.next_2d();
        let Some(bs) = bsdf.sample(albedo, ng, ns, wo, u, uv) else {
            break;
        };
        thr = mul(thr, bs.weight);
        eta *= bs.eta;
        prev_pdf = bs.pdf;
        prev_delta = bs.delta;
        depth += 1;
        // Russian roulette (Arvo & Kirk 1990), as Mitsuba 3 does it.
        let tmaxc = max_comp(thr);
        if depth >= s.rr_depth {
            let q = (tmaxc * eta * eta).min(0.95);
            if rng.next_f32() >= q {
                break;
            }
            thr = scale(thr, 1.0 / q);
        }
        if tmaxc <= 0.0 || !tmaxc.is_finite() {
            break;
        }
        let side = if dot(ng, bs.wi) > 0.0 {
            ng
        } else {
            scale(ng, -1.0)
        };
        org = sc.offset(p, side);
        dir = bs.wi;
        tmax = f32::INFINITY;
    }
    // A path that ended after estimating direct light still owes its shadow ray.
    if let Some(d) = pending {
        l = d.finish(sc, l);
    }
    l
}

/// Mitsuba's Gaussian filter: exp(-x^2 / (2 sigma^2)) minus its value at the radius,
/// sigma = 0.5 px, radius 2 px.
#[inline]
fn gaussian_1d(x: f32) -> f32 {
    const INV_2S2: f32 = 1.0 / (2.0 * 0.25);
    let edge = (-4.0 * INV_2S2).exp();
    ((-x * x * INV_2S2).exp() - edge).max(0.0)
}

const TILE: u32 = 16;
const MARGIN: i64 = 2;

struct TileOut {
    x0: u32,
    y0: u32,
    /// Splat sums (r, g, b, weight) over the tile grown by MARGIN on each side.
    splat: Vec<[f32; 4]>,
    /// Per own pixel: variance of the pixel mean.
    var: Vec<[f32; 3]>,
}

/// Renders `cam`'s view of `sc`. Returns the colour image (linear radiance) and, per
/// pixel, the variance of the pixel's estimate (sample variance of its own samples over
/// spp, before filtering). `progress` receives the fraction of tiles done. Scenes the
/// four-lane loop handles (`path_lanes::handles`: every material diffuse) are traced four
/// paths at a time, with the same result bit for bit.
pub fn render(
    sc: &RenderScene,
    cam: &PinholeCamera,
    s: &PathSettings,
    progress: &(dyn Fn(f64) + Sync),
) -> (Image, Image) {
    render_opts(sc, cam, s, progress, true)
}

/// `render`, with the four-lane loop allowed (`lanes`) or not (to measure what it buys
/// and to check that both loops agree).
pub fn render_opts(
    sc: &RenderScene,
    cam: &PinholeCamera,
    s: &PathSettings,
    progress: &(dyn Fn(f64) + Sync),
    lanes: bool,
) -> (Image, Image) {
    let lanes = lanes && path_lanes::handles(sc);
    // Pixels per batch of samples for the four-lane loop (about 16k samples, so lanes
    // seldom wait for a batch's last paths; the scalar loop goes pixel by pixel).
    let ppc = if lanes {
        (16384 / s.spp as usize).max(1)
    } else {
        1
    };
    let (w, h) = (cam.width, cam.height);
    let mut tiles = Vec::new();
    for y0 in (0..h).step_by(TILE as usize) {
        for x0 in (0..w).step_by(TILE as usize) {
            tiles.push((x0, y0));
        }
    }
    let done = AtomicUsize::new(0);
    let ntiles = tiles.len();
    let pw = (TILE as i64 + 2 * MARGIN) as usize;
    let outs: Vec<TileOut> = tiles
        .par_iter()
        .map(|&(x0, y0)| {
            let x1 = (x0 + TILE).min(w);
            let y1 = (y0 + TILE).min(h);
            let mut splat = vec![[0.0f32; 4]; pw * pw];
            let mut var = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
            let mut stacks = TraceStacks::new();
            let pixels: Vec<(u32, u32)> =
                (y0..y1).flat_map(|y| (x0..x1).map(move |x| (x, y))).collect();
            let mut samples: Vec<Sample> = Vec::new();
            for chunk in pixels.chunks(ppc) {
                if lanes {
                    let jobs: Vec<Job> = chunk
                        .iter()
                        .flat_map(|&(x, y)| (0..s.spp).map(move |k| (x, y, k)))
                        .collect();
                    samples = path_lanes::trace(sc, cam, s, &jobs, &mut stacks);
                } else {
                    samples.clear();
                    for &(x, y) in chunk {
                        let pix = y as u64 * w as u64 + x as u64;
                        for k in 0..s.spp {
                            let mut rng = Pcg32::for_sample(pix, k as u64, s.seed);
                            let [ux, uy] = rng.next_2d();
                            let fx = x as f32 + ux;
                            let fy = y as f32 + uy;
                            let dir = cam.ray_dir(fx, fy);
                            let c = radiance(sc, cam.eye, dir, cam.far, &mut rng, s, &mut stacks);
                            samples.push(Sample { c, fx, fy });
                        }
                    }
                }
                for (j, &(x, y)) in chunk.iter().enumerate() {
                    let (mut s1, mut s2) = ([0.0f64; 3], [0.0f64; 3]);
                    let own = &samples[j * s.spp as usize..(j + 1) * s.spp as usize];
                    for &Sample { c, fx, fy } in own {
                        let mut c = c;
                        if !c.iter().all(|v| v.is_finite()) {
                            c = [0.0; 3];
                        }
                        for j in 0..3 {
                            s1[j] += c[j] as f64;
                            s2[j] += (c[j] as f64) * (c[j] as f64);
                        }
                        match s.filter {
                            Filter::Box => {
                                let i = (y - y0) as usize + MARGIN as usize;
                                let jx = (x - x0) as usize + MARGIN as usize;
                                let a = &mut splat[i * pw + jx];
                                a[0] += c[0];
                                a[1] += c[1];
                                a[2] += c[2];
                                a[3] += 1.0;
                            }
                            Filter::Gaussian => {
                                // Pixels whose centres lie within the radius.
                                let cx0 = (fx - 0.5 - 2.0).ceil() as i64;
                                let cy0 = (fy - 0.5 - 2.0).ceil() as i64;
                                let mut wx = [0.0f32; 5];
                                let mut wy = [0.0f32; 5];
                                for k in 0..5 {
                                    wx[k] = gaussian_1d((cx0 + k as i64) as f32 + 0.5 - fx);
                                    wy[k] = gaussian_1d((cy0 + k as i64) as f32 + 0.5 - fy);
                                }
                                for (ky, wyk) in wy.iter().enumerate() {
                                    let py = cy0 + ky as i64;
                                    if *wyk <= 0.0 || py < 0 || py >= h as i64 {
                                        continue;
                                    }
                                    let i = (py - y0 as i64 + MARGIN) as usize;
                                    for (kx, wxk) in wx.iter().enumerate() {
                                        let px = cx0 + kx as i64;
                                        if *wxk <= 0.0 || px < 0 || px >= w as i64 {
                                            continue;
                                        }
                                        let jx = (px - x0 as i64 + MARGIN) as usize;
                                        let wt = wxk * wyk;
                                        let a = &mut splat[i * pw + jx];
                                        a[0] += c[0] * wt;
                                        a[1] += c[1] * wt;
                                        a[2] += c[2] * wt;
                                        a[3] += wt;
                                    }
                                }
                            }
                        }
                    }
                    let n = s.spp as f64;
                    let mut v = [0.0f32; 3];
                    if s.spp > 1 {
                        for j in 0..3 {
                            let m = s1[j] / n;
                            v[j] = (((s2[j] / n - m * m) * n / (n - 1.0)).max(0.0) / n) as f32;
                        }
                    }
                    var.push(v);
                }
            }
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress(d as f64 / ntiles as f64);
            TileOut { x0, y0, splat, var }
        })
        .collect();
    // Gather the splats (in tile order, so the sums are deterministic).
    let mut acc = vec![[0.0f64; 4]; (w * h) as usize];
    let mut variance = Image::new(w, h, [0.0, 0.0, 0.0, 1.0]);
    for t in &outs {
        for i in 0..pw {
            let py = t.y0 as i64 - MARGIN + i as i64;
            if py < 0 || py >= h as i64 {
                continue;
            }
            for j in 0..pw {
                let px = t.x0 as i64 - MARGIN + j as i64;
                if px < 0 || px >= w as i64 {
                    continue;
                }
                let a = &mut acc[py as usize * w as usize + px as usize];
                let sv = t.splat[i * pw + j];
                for k in 0..4 {
                    a[k] += sv[k] as f64;
                }
            }
        }
        let tw = (t.x0 + TILE).min(w) - t.x0;
        for (k, v) in t.var.iter().enumerate() {
            let x = t.x0 + k as u32 % tw;
            let y = t.y0 + k as u32 / tw;
            variance.set(x, y, [v[0], v[1], v[2], 1.0]);
        }
    }
    let mut color = Image::new(w, h, [0.0, 0.0, 0.0, 1.0]);
    for (px, a) in color.pixels.iter_mut().zip(&acc) {
        if a[3] > 0.0 {
            *px = [
                (a[0] / a[3]) as f32,
                (a[1] / a[3]) as f32,
                (a[2] / a[3]) as f32,
                1.0,
            ];
        }
    }
    (color, variance)
}

/// Flattens `scene` and renders it from `camera` (or the scene's own camera).
pub fn render_path(
    scene: &Scene,
    camera: Option<&Camera>,
    s: &PathSettings,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<(Image, Image), String> {
    let (sc, cam) = prepare(scene, camera, s.crease_deg)?;
    Ok(render(&sc, &cam, s, progress))
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Path traces a scene (NEE + BSDF sampling with MIS, Russian roulette); linear colour and per-pixel variance.");
    b.add_input::<Scene>("scene");
    b.add_input::<Camera>("camera")
        .optional()
        .doc("Overrides the scene's camera.");
    b.add_input::<i64>("spp")
        .default(16i64)
        .range(1.0, 1e6)
        .doc("Samples per pixel.");
    b.add_input::<i64>("max_depth")
        .default(8i64)
        .range(-1.0, 1e4)
        .doc("Longest path in segments, as in Mitsuba: 1 = emitters only, 2 = direct light, 8 = at most 7 bounces; -1 = unbounded.");
    b.add_input::<i64>("rr_depth")
        .default(5i64)
        .range(1.0, 1e4)
        .doc("Bounces before Russian roulette starts.");
    b.add_input::<i64>("seed").default(0i64).doc("Random seed.");
    b.add_choice::<Filter>("filter")
        .doc("Reconstruction filter: Mitsuba's gaussian (stddev 0.5 px, radius 2 px) or a one-pixel box.");
    b.add_choice::<Strategy>("strategy")
        .doc("Emitter + BSDF sampling with the power heuristic, or either alone.");
    declare_crease(b);
    b.add_output::<Image>("color").doc("Linear radiance.");
    b.add_output::<Image>("variance")
        .doc("Variance of each pixel's estimate (its own samples, unfiltered).");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let scene: Arc<Scene> = ctx.input("scene")?;
    let camera: Option<Arc<Camera>> = ctx.input_opt("camera")?;
    let spp: i64 = ctx.input("spp")?;
    let max_depth: i64 = ctx.input("max_depth")?;
    let rr_depth: i64 = ctx.input("rr_depth")?;
    let seed: i64 = ctx.input("seed")?;
    let filter = ctx.choice::<Filter>("filter")?;
    let strategy = ctx.choice::<Strategy>("strategy")?;
    let crease_deg = crease_input(ctx)?;
    if !(1..=1_000_000).contains(&spp) {
        return Err(NodeError::invalid(
            "spp",
            format!("spp {spp} must be in 1..=1000000"),
        ));
    }
    if max_depth == 0 || max_depth < -1 {
        return Err(NodeError::invalid(
            "max_depth",
            format!("max_depth {max_depth} must be -1 (unbounded) or at least 1"),
        ));
    }
    if rr_depth < 1 {
        return Err(NodeError::invalid(
            "rr_depth",
            "rr_depth must be at least 1",
        ));
    }
    let s = PathSettings {
        spp: spp as u32,
        max_depth: if max_depth < 0 {
            u32::MAX
        } else {
            max_depth.min(u32::MAX as i64) as u32
        },
        rr_depth: rr_depth.min(u32::MAX as i64) as u32,
        seed: seed as u64,
        filter,
        strategy,
        crease_deg,
    };
    // Per pixel: the f64 accumulator (32 bytes), colour and variance images (16 each), the
    // tiles' splat margins and variances (about 40).
    reserve_image(ctx, &scene, camera.as_deref(), 104)?;
    let report = ctx.progress_fn();
    let t0 = std::time::Instant::now();
    let (color, variance) =
        render_path(&scene, camera.as_deref(), &s, &report).map_err(trace_error)?;
    let secs = t0.elapsed().as_secs_f64();
    let paths = color.width as f64 * color.height as f64 * s.spp as f64;
    ctx.log(format!(
        "{}x{} at {} spp in {:.3} s ({:.2} Mpaths/s)",
        color.width,
        color.height,
        s.spp,
        secs,
        paths / secs.max(1e-9) / 1e6
    ));
    ctx.set_output("color", color);
    ctx.set_output("variance", variance);
    Ok(())
}

/// Registers `render_path`.
pub fn register(r: &mut Registry) {
    r.add("render_path", declare, execute);
}
