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
//! (pixel, sample index, seed), so images are identical whatever the thread count. This
//! file holds the estimator for one path (`radiance`) and the node; the film (tiles, the
//! box or Gaussian reconstruction filter, variance) is `path_film.rs`, and the estimator
//! run on eight paths at a time for diffuse scenes is `path_lanes.rs`.

use super::bvh::{Hit, Segment, Slab, TraceStacks};
use super::direct::{delta_lights, environment_nee, Vertex};
pub use super::path_film::{render, render_opts, Shortcuts};
use super::render_scene::{prepare_cached, RenderScene, TraceError, SHADOW_END};
use super::sampling::{add, dot, max_comp, mul, power_heuristic, scale, sub, Pcg32, V3};
use super::tracer_node::{crease_input, declare_crease, reserve_image, trace_error};
use cgnodes_api::prelude::*;

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
    /// Traces the next segment's ray together with this estimate's shadow ray (two
    /// traversals interleaved): the segment's hit, and `l` with the estimates added.
    #[inline(always)]
    fn trace_with<S: Slab>(
        &self,
        sc: &RenderScene,
        stacks: &mut TraceStacks<S>,
        ray: Segment,
        l: V3,
    ) -> (Option<Hit>, V3) {
        let (hit, blocked) = match self.nee {
            Some((shadow, _)) => sc.bvh.intersect_occluded_in(stacks, ray, shadow),
            None => (sc.bvh.closest_in(stacks, ray), false),
        };
        (hit, self.add_to(l, blocked))
    }

    /// Adds the estimates to `l`, the emitter sample's only when `blocked` is false.
    #[inline]
    fn add_to(&self, l: V3, blocked: bool) -> V3 {
        let nee = self.nee.filter(|_| !blocked).map(|(_, c)| c);
        add_direct(l, nee, self.delta, self.env)
    }

    /// Traces the shadow ray alone (the path ends here) and adds the estimates to `l`.
    #[inline]
    fn finish(&self, sc: &RenderScene, l: V3) -> V3 {
        let blocked = self
            .nee
            .is_some_and(|((o, d, t), _)| sc.bvh.occluded(o, d, t));
        self.add_to(l, blocked)
    }
}

/// `l` plus a vertex's direct light: the emitter sample's contribution (`nee`, when its
/// shadow ray was not blocked), the point and directional lights' and the environment
/// sample's, in this order (both path loops add them so, for the same bits).
#[inline(always)]
pub(crate) fn add_direct(l: V3, nee: Option<V3>, delta: V3, env: Option<V3>) -> V3 {
    let mut l = l;
    if let Some(c) = nee {
        l = add(l, c);
    }
    l = add(l, delta);
    if let Some(e) = env {
        l = add(l, e);
    }
    l
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

/// Radiance arriving at `org` from direction `-dir` (unit `dir`), estimated with one path
/// whose first segment (`org + t dir`, `t < tmax`) hits `first` (the caller traced it).
/// `stacks` are the traversal stacks the path's rays use (one set per thread, reused).
/// Inlined into its callers: the x86-64-v3 build of `path_one` needs it built with AVX.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn radiance<S: Slab>(
    sc: &RenderScene,
    org: V3,
    dir: V3,
    tmax: f32,
    first: Option<Hit>,
    rng: &mut Pcg32,
    s: &PathSettings,
    stacks: &mut TraceStacks<S>,
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
    let mut first = Some(first);
    loop {
        let hit = match pending.take() {
            None => match first.take() {
                Some(hit) => hit,
                None => sc.bvh.closest_in(stacks, (org, dir, tmax)),
            },
            Some(d) => {
                let (hit, lit) = d.trace_with(sc, stacks, (org, dir, tmax), l);
                l = lit;
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
        let ng = sc.normal(tri);
        let mat = sc.material(tri);
        let wo = scale(dir, -1.0);
        let p = add(org, scale(dir, hit.t));

        // Emission found by the ray just traced (Veach 1997, eq. 9.13 for the weight).
        if mat.is_emitter() {
            let first = depth == 0 || prev_delta;
            if let Some((le, w)) = emission_found(sc, s.strategy, &hit, wo, first, prev_pdf) {
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
            let v = Vertex {
                p,
                wo,
                sp: &sp,
                bsdf,
            };
            pending = Some(direct_light(sc, s.strategy, &v, thr, rng));
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
        let Some(survived) = russian_roulette(thr, eta, depth >= s.rr_depth, rng) else {
            break;
        };
        thr = survived;
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

/// The radiance `Le` a triangle emits toward `wo` where the path's ray `hit` it, with its
/// MIS weight against the emitter sampling of the previous vertex (`found_weight`); `None`
/// when it emits nothing that way.
#[inline(always)]
fn emission_found(
    sc: &RenderScene,
    strategy: Strategy,
    hit: &Hit,
    wo: V3,
    first: bool,
    prev_pdf: f32,
) -> Option<(V3, f32)> {
    let tri = hit.prim as usize;
    let le = sc.emitted(hit.prim, wo);
    if max_comp(le) > 0.0 {
        let w = found_weight(strategy, first, prev_pdf, || {
            let cos_l = dot(sc.normal(tri as u32), wo).abs();
            sc.light_pdf_area[tri] * hit.t * hit.t / cos_l
        });
        return Some((le, w));
    }
    None
}

/// Russian roulette (Arvo & Kirk 1990) as Mitsuba 3 does it: once `active`, the path goes
/// on with probability `min(max(thr) eta², 0.95)` and its throughput divided by it. `None`
/// when the path ends here, also when its throughput is zero or not finite.
#[inline(always)]
fn russian_roulette(thr: V3, eta: f32, active: bool, rng: &mut Pcg32) -> Option<V3> {
    let tmaxc = max_comp(thr);
    let mut thr = thr;
    if active {
        let q = (tmaxc * eta * eta).min(0.95);
        if rng.next_f32() >= q {
            return None;
        }
        thr = scale(thr, 1.0 / q);
    }
    if tmaxc <= 0.0 || !tmaxc.is_finite() {
        return None;
    }
    Some(thr)
}

/// The direct light at a non-specular path vertex, estimated now and added once its shadow
/// rays are traced: one area-emitter sample (next-event estimation), the point and
/// directional lights, and one environment sample, each times the path throughput `thr`.
/// The random numbers are drawn in this order: emitter, environment.
#[inline(always)]
fn direct_light(
    sc: &RenderScene,
    strategy: Strategy,
    v: &Vertex,
    thr: V3,
    rng: &mut Pcg32,
) -> Deferred {
    let mut d = Deferred {
        nee: None,
        delta: [0.0; 3],
        env: None,
    };
    if strategy != Strategy::Bsdf {
        let u = rng.next_f32();
        let uv = rng.next_2d();
        d.nee = area_emitter_nee(sc, v, thr, u, uv, strategy == Strategy::Mis);
    }
    if !sc.lights.is_empty() {
        d.delta = mul(thr, delta_lights(sc, v));
    }
    if sc.env.is_some() && strategy != Strategy::Bsdf {
        let u = rng.next_2d();
        let le = environment_nee(sc, v, u, strategy == Strategy::Mis);
        d.env = Some(mul(thr, le));
    }
    d
}

/// Next-event estimation on the area emitters (Veach 1997, §9.2.2; MIS weight eq. 9.13 with
/// the power heuristic when `mis`): the emitter point chosen by `u`, `uv`, its shadow ray
/// (origin, unnormalized direction, end) and the contribution `thr f Le w / p_light` it
/// carries when unblocked; `None` when the sample cannot contribute.
#[inline(always)]
fn area_emitter_nee(
    sc: &RenderScene,
    v: &Vertex,
    thr: V3,
    u: f32,
    uv: [f32; 2],
    mis: bool,
) -> Option<(Segment, V3)> {
    let ls = sc.sample_emitter(u, uv)?;
    let (p, ng) = (v.p, v.sp.ng);
    let dv = sub(ls.p, p);
    let dist2 = dot(dv, dv);
    let dist = dist2.sqrt();
    // Written as positive tests so that a NaN anywhere drops the sample.
    if dist > 0.0 {
        let wi = scale(dv, 1.0 / dist);
        let le = ls.emitted(scale(wi, -1.0));
        let cos_l = dot(ls.n, wi).abs();
        if max_comp(le) > 0.0 && cos_l > 0.0 {
            let (f, bsdf_pdf) = v.bsdf.eval_pdf(v.sp.albedo, ng, v.sp.ns, v.wo, wi);
            if max_comp(f) > 0.0 {
                let side = if dot(ng, wi) > 0.0 {
                    ng
                } else {
                    scale(ng, -1.0)
                };
                let o = sc.offset(p, side);
                let p_light = ls.pdf_area * dist2 / cos_l;
                let w = if mis {
                    power_heuristic(p_light, bsdf_pdf)
                } else {
                    1.0
                };
                let c = scale(mul(thr, mul(f, le)), w / p_light);
                return Some(((o, sub(ls.p, o), SHADOW_END), c));
            }
        }
    }
    None
}

/// Flattens `scene` and renders it from `camera` (or the scene's own camera).
pub fn render_path(
    scene: &Scene,
    camera: Option<&Camera>,
    s: &PathSettings,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<(Image, Image), TraceError> {
    let (sc, cam, _) = prepare_cached(scene, camera, s.crease_deg)?;
    Ok(render(&sc, &cam, s, progress))
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Path traces a scene (NEE + BSDF sampling with MIS, Russian roulette); linear colour and per-pixel variance.");
    b.add_input::<Scene>("scene");
    b.add_input::<Camera>("camera")
        .optional()
        .doc("Overrides the scene's camera.");
    let d = PathSettings::default();
    b.add_input::<i64>("spp")
        .default(d.spp as i64)
        .range(1.0, 1e6)
        .doc("Samples per pixel.");
    b.add_input::<i64>("max_depth")
        .default(d.max_depth as i64)
        .range(-1.0, 1e4)
        .doc("Longest path in segments, as in Mitsuba: 1 = emitters only, 2 = direct light, 8 = at most 7 bounces; -1 = unbounded.");
    b.add_input::<i64>("rr_depth")
        .default(d.rr_depth as i64)
        .range(1.0, 1e4)
        .doc("Bounces before Russian roulette starts.");
    b.add_input::<i64>("seed")
        .default(d.seed as i64)
        .doc("Random seed.");
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
    // The declared ranges are checked by the runtime on literal and linked values alike;
    // only max_depth's hole at 0 is left to check here.
    if max_depth == 0 {
        return Err(NodeError::invalid(
            "max_depth",
            format!("max_depth {max_depth} must be -1 (unbounded) or at least 1"),
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
    let (sc, cam, reused) =
        prepare_cached(&scene, camera.as_deref(), s.crease_deg).map_err(trace_error)?;
    let prep = t0.elapsed().as_secs_f64();
    let (color, variance) = render(&sc, &cam, &s, &report);
    let secs = t0.elapsed().as_secs_f64();
    let paths = color.width as f64 * color.height as f64 * s.spp as f64;
    ctx.log(format!(
        "{}x{} at {} spp in {:.3} s ({:.2} Mpaths/s); scene {} in {:.3} s",
        color.width,
        color.height,
        s.spp,
        secs,
        paths / secs.max(1e-9) / 1e6,
        if reused {
            "reused from the last render"
        } else {
            "prepared"
        },
        prep
    ));
    ctx.set_output("color", color);
    ctx.set_output("variance", variance);
    Ok(())
}

/// Registers `render_path`.
pub fn register(r: &mut Registry) {
    r.add("render_path", declare, execute);
}
