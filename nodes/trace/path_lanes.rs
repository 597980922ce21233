//! `render_path`'s estimator run on eight paths at a time: the scalar work of a path vertex
//! (tracing, random numbers, material and emitter look-ups) stays per path, and the
//! arithmetic of shading it (next-event geometry, the diffuse BSDF's value and density,
//! the power heuristic, cosine-weighted sampling, ray offsets) runs on eight lanes, one path
//! per lane, with masks in place of branches (`lane_math::Lane`: two SSE halves in the
//! baseline build, one AVX register in the x86-64-v3 one). A lane whose path ends takes the next
//! pixel sample at once, so the lanes stay full (the path regeneration of wavefront path
//! tracers: Laine, Karras and Aila 2013, "Megakernels Considered Harmful").
//!
//! Every lane performs the scalar `radiance`'s floating-point operations in the same order
//! (Rust never contracts to FMA; SSE's and AVX's add, multiply, divide and square root are
//! IEEE correctly rounded like their scalar forms) and draws the same random numbers from the
//! path's own stream, so a sample's radiance is bit for bit the scalar one
//! (`lane_paths_change_no_bit` in `tests/it/trace.rs`). It covers scenes whose
//! materials are all diffuse (textured or not), under any strategy and any lights: the
//! point, directional and environment lights' estimates are made per lane, in the scalar
//! loop's code. Scenes with a glossy or specular material take the scalar loop
//! (`handles`).

use super::bsdf::Bsdf;
#[cfg(target_arch = "x86_64")]
use super::bvh::Avx;
use super::bvh::{Hit, Segment, Slab, TraceStacks};
use super::camera_sample::{Batch, Sample, Starts};
use super::direct::{delta_lights, environment_nee, Vertex};
#[cfg(target_arch = "x86_64")]
use super::lane_avx::Avx8;
use super::lane_math::{get, put, Lane, L};
use super::render_path::{add_direct, found_weight, PathSettings, Strategy};
use super::render_scene::{RenderScene, SHADOW_END};
use super::sampling::{add, dot, max_comp, mul, scale, Pcg32, V3};

mod shade;
use shade::shade;

/// Whether the lane loop renders `sc`: every material is diffuse (the loop's
/// shading arithmetic is the diffuse lobe's); every strategy, filter and light is handled.
pub fn handles(sc: &RenderScene) -> bool {
    sc.materials.iter().all(|m| m.bsdf == Bsdf::Diffuse)
}

/// Per-lane inputs of the shading step, gathered by the scalar part.
#[derive(Default)]
struct Gather {
    /// Hit distance.
    t: [f32; L],
    ng: [[f32; L]; 3],
    ns: [[f32; L]; 3],
    albedo: [[f32; L]; 3],
    /// The emitter sample (point, normal, area density, emission, two-sided), if any.
    has_ls: [bool; L],
    ls_p: [[f32; L]; 3],
    ls_n: [[f32; L]; 3],
    ls_pdf: [f32; L],
    ls_le: [[f32; L]; 3],
    ls_two: [bool; L],
    /// The two numbers of the BSDF sample.
    bsdf_uv: [[f32; L]; 2],
    /// The point and directional lights' estimate (times the throughput), and the
    /// environment sample's, when one was drawn.
    delta: [V3; L],
    env: [Option<V3>; L],
}

/// What the lanes carry between segments; vectors axis by axis (`[axis][lane]`), so the
/// shading step loads and stores them whole.
struct Lanes {
    /// Index of the job in each lane (`IDLE` when none).
    job: [usize; L],
    rng: [Pcg32; L],
    org: [[f32; L]; 3],
    dir: [[f32; L]; 3],
    tmax: [f32; L],
    thr: [[f32; L]; 3],
    l: [V3; L],
    /// The density of the BSDF sample that led to the current vertex. Every bounce is
    /// diffuse, so the scalar loop's `prev_delta` is "depth is 0" here, and its `eta`
    /// stays 1.
    prev_pdf: [f32; L],
    depth: [u32; L],
    /// The camera ray's hit, found when the lane took the sample.
    first: [Option<Hit>; L],
    /// Direct light estimated at the previous vertex waiting for its shadow ray (as
    /// `render_path::Deferred`): whether there is one, whether it has an emitter sample,
    /// that sample's shadow segment and its contribution when unblocked.
    pending: [bool; L],
    nee: [bool; L],
    delta: [V3; L],
    env: [Option<V3>; L],
    seg_o: [[f32; L]; 3],
    seg_d: [[f32; L]; 3],
    nee_c: [[f32; L]; 3],
    /// Ended paths whose last shadow ray has not been traced yet (at most `ORPHANS`).
    orphans: Vec<Orphan>,
}

const IDLE: usize = usize::MAX;

/// Orphaned shadow rays kept at most; beyond, two are traced together.
const ORPHANS: usize = 8;

/// The last shadow ray of an ended path, kept until another lane traces a segment that
/// has no shadow ray of its own, so that the two walks run interleaved instead of each
/// alone (a tenth of the box render went to lone walks: docs/path_tracing.md, twelfth
/// round). It holds the path's radiance so far and its pending direct light, added by
/// `add_direct` as `Lanes::add_pending` would.
#[derive(Clone, Copy, Debug)]
struct Orphan {
    seg: Segment,
    l: V3,
    nee_c: V3,
    delta: V3,
    env: Option<V3>,
    job: usize,
}

impl Orphan {
    /// Stores the path's radiance once its shadow ray is known to be `blocked` or not.
    #[inline(always)]
    fn resolve(&self, blocked: bool, out: &mut [Sample]) {
        let nee = (!blocked).then_some(self.nee_c);
        out[self.job].c = add_direct(self.l, nee, self.delta, self.env);
    }
}

impl Lanes {
    fn new() -> Lanes {
        Lanes {
            job: [IDLE; L],
            rng: std::array::from_fn(|_| Pcg32::new(0, 0)),
            org: [[0.0; L]; 3],
            dir: [[0.0; L]; 3],
            tmax: [0.0; L],
            thr: [[0.0; L]; 3],
            l: [[0.0; 3]; L],
            prev_pdf: [0.0; L],
            depth: [0; L],
            first: [None; L],
            pending: [false; L],
            nee: [false; L],
            delta: [[0.0; 3]; L],
            env: [None; L],
            seg_o: [[0.0; L]; 3],
            seg_d: [[0.0; L]; 3],
            nee_c: [[0.0; L]; 3],
            orphans: Vec::with_capacity(ORPHANS + 1),
        }
    }

    /// The closest hit along a segment that has no shadow ray beside it: traced together
    /// with an orphaned shadow ray when there is one.
    #[inline(always)]
    fn lone<S: Slab>(
        &mut self,
        sc: &RenderScene,
        seg: Segment,
        stacks: &mut TraceStacks<S>,
        out: &mut [Sample],
    ) -> Option<Hit> {
        match self.orphans.pop() {
            Some(o) => {
                let (hit, blocked) = sc.bvh.intersect_occluded_in(stacks, seg, o.seg);
                o.resolve(blocked, out);
                hit
            }
            None => sc.bvh.single_in::<false, _>(stacks, seg),
        }
    }

    /// Traces the orphaned shadow rays two at a time until at most `keep` are left.
    #[inline(always)]
    fn flush_orphans<S: Slab>(
        &mut self,
        sc: &RenderScene,
        keep: usize,
        stacks: &mut TraceStacks<S>,
        out: &mut [Sample],
    ) {
        while self.orphans.len() > keep {
            let a = self.orphans.pop().expect("more than `keep` orphans");
            match self.orphans.pop() {
                Some(b) => {
                    let (ba, bb) = sc.bvh.occluded_pair_in(stacks, a.seg, b.seg);
                    a.resolve(ba, out);
                    b.resolve(bb, out);
                }
                None => a.resolve(sc.bvh.single_in::<true, _>(stacks, a.seg).is_some(), out),
            }
        }
    }

    /// Adds lane `i`'s pending direct light (`add_direct`), the emitter sample's only when
    /// it has one and its shadow ray is not `blocked`.
    #[inline(always)]
    fn add_pending<const LIGHTS: bool>(&mut self, i: usize, blocked: bool) {
        let nee = (self.nee[i] && !blocked).then(|| get(&self.nee_c, i));
        self.l[i] = if LIGHTS {
            add_direct(self.l[i], nee, self.delta[i], self.env[i])
        } else {
            // No point, directional or environment light: their terms are zero.
            nee.map_or(self.l[i], |c| add(self.l[i], c))
        };
        self.pending[i] = false;
    }

    /// Ends lane `i`'s path and stores its radiance, or, when a shadow ray is still to be
    /// traced, leaves that to an `Orphan`.
    #[inline(always)]
    fn finish<const LIGHTS: bool, S: Slab>(
        &mut self,
        i: usize,
        sc: &RenderScene,
        stacks: &mut TraceStacks<S>,
        out: &mut [Sample],
    ) {
        if self.pending[i] && self.nee[i] {
            self.orphans.push(Orphan {
                seg: (get(&self.seg_o, i), get(&self.seg_d, i), SHADOW_END),
                l: self.l[i],
                nee_c: get(&self.nee_c, i),
                delta: self.delta[i],
                env: self.env[i],
                job: self.job[i],
            });
            self.pending[i] = false;
            self.flush_orphans(sc, ORPHANS, stacks, out);
        } else {
            if self.pending[i] {
                self.add_pending::<LIGHTS>(i, false);
            }
            out[self.job[i]].c = self.l[i];
        }
        self.job[i] = IDLE;
    }
}

/// Traces the batch's pixel samples and returns their radiance and film positions, in
/// `jobs`' order, as `render_path`'s per-sample loop computes them. `v3`: whether the
/// x86-64-v3 build may run where the CPU has it (the same bits; off to compare).
pub fn trace(b: Batch, stacks: &mut TraceStacks, v3: bool) -> Vec<Sample> {
    #[cfg(target_arch = "x86_64")]
    if let Some(avx) = Avx::detect_v3().filter(|_| v3) {
        // SAFETY: `trace_avx2` needs exactly the features `detect_v3` found on this CPU.
        return unsafe { trace_avx2(b, avx) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = v3;
    trace_body::<true, _, wide::f32x8>(b, stacks)
}

/// `trace` compiled for x86-64-v3 (AVX2 and its companions), chosen at run time so that
/// the binary still starts on older CPUs. The same code as the baseline build: three-operand
/// VEX forms of the same SSE instructions (Rust never contracts to FMA), so the same bits,
/// in about 5 % fewer instructions (docs/path_tracing.md, "How it runs"), with the node box
/// test on 256-bit registers (`Avx`, on stacks of its own).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
fn trace_avx2(b: Batch, avx: Avx) -> Vec<Sample> {
    let stacks = &mut TraceStacks::with_slab(avx);
    if b.sc.lights.is_empty() && b.sc.env.is_none() {
        trace_body::<false, _, Avx8>(b, stacks)
    } else {
        trace_body::<true, _, Avx8>(b, stacks)
    }
}

/// `trace`'s loop, inlined into both builds. `LIGHTS` is whether the scene may have point,
/// directional or environment lights; without, their per-vertex estimates (zero) are not
/// gathered, carried or added (the x86-64-v3 build is made both ways, the baseline one only
/// with `LIGHTS`).
#[inline(always)]
fn trace_body<const LIGHTS: bool, S: Slab, F: Lane>(
    b: Batch,
    stacks: &mut TraceStacks<S>,
) -> Vec<Sample> {
    let Batch { sc, cam, s, .. } = b;
    let mut out = vec![Sample::default(); b.jobs.len()];
    let mut ln = Lanes::new();
    let mut g = Gather::default();
    let mut starts = Starts::<F>::new(b);
    loop {
        // Idle lanes take the next pixel samples (the camera ray, as `render` makes it).
        for i in 0..L {
            if ln.job[i] != IDLE {
                continue;
            }
            let Some(cs) = starts.next() else { break };
            out[cs.job].fx = cs.fx;
            out[cs.job].fy = cs.fy;
            ln.job[i] = cs.job;
            ln.rng[i] = cs.rng;
            put(&mut ln.org, i, cam.eye);
            put(&mut ln.dir, i, cs.dir);
            ln.tmax[i] = cam.far;
            ln.first[i] = cs.hit;
            put(&mut ln.thr, i, [1.0; 3]);
            ln.l[i] = [0.0; 3];
            ln.prev_pdf[i] = 0.0;
            ln.depth[i] = 0;
            ln.pending[i] = false;
        }
        if ln.job.iter().all(|&j| j == IDLE) {
            ln.flush_orphans(sc, 0, stacks, &mut out);
            break;
        }
        let mut go = [false; L];
        for (i, go) in go.iter_mut().enumerate() {
            *go = ln.job[i] != IDLE
                && visit::<LIGHTS, _>(sc, s, &mut ln, i, &mut g, stacks, &mut out);
        }
        if go.iter().any(|&b| b) {
            shade::<LIGHTS, _, F>(sc, s, &mut ln, &g, go, stacks, &mut out);
        }
    }
    out
}

/// The scalar part of a vertex on lane `i`: trace the segment (with the pending shadow
/// ray), add emission found, and gather what the shading step needs, drawing the vertex's
/// random numbers in the scalar loop's order. Returns false when the path has ended.
#[inline(always)]
fn visit<const LIGHTS: bool, S: Slab>(
    sc: &RenderScene,
    s: &PathSettings,
    ln: &mut Lanes,
    i: usize,
    g: &mut Gather,
    stacks: &mut TraceStacks<S>,
    out: &mut [Sample],
) -> bool {
    let (org, dir, tmax) = (get(&ln.org, i), get(&ln.dir, i), ln.tmax[i]);
    let hit: Option<Hit> = if ln.pending[i] {
        let (hit, blocked) = if ln.nee[i] {
            let shadow = (get(&ln.seg_o, i), get(&ln.seg_d, i), SHADOW_END);
            sc.bvh
                .intersect_occluded_in(stacks, (org, dir, tmax), shadow)
        } else {
            (ln.lone(sc, (org, dir, tmax), stacks, out), false)
        };
        ln.add_pending::<LIGHTS>(i, blocked);
        hit
    } else if ln.depth[i] == 0 {
        ln.first[i]
    } else {
        ln.lone(sc, (org, dir, tmax), stacks, out)
    };
    let first = ln.depth[i] == 0;
    let Some(hit) = hit else {
        // The ray escapes: the environment's radiance, weighted like an emitter hit.
        if let Some(env) = &sc.env {
            let w = found_weight(s.strategy, first, ln.prev_pdf[i], || env.pdf(dir));
            ln.l[i] = add(ln.l[i], scale(mul(get(&ln.thr, i), env.eval(dir)), w));
        }
        ln.finish::<LIGHTS, _>(i, sc, stacks, out);
        return false;
    };
    let tri = hit.prim;
    let face = sc.face(tri);
    let mat = &sc.materials[face.material()];
    let wo = scale(dir, -1.0);
    if mat.is_emitter() {
        let le = sc.emitted(tri, wo);
        if max_comp(le) > 0.0 {
            let w = found_weight(s.strategy, first, ln.prev_pdf[i], || {
                let cos_l = dot(face.n, wo).abs();
                sc.light_pdf_area[tri as usize] * hit.t * hit.t / cos_l
            });
            ln.l[i] = add(ln.l[i], scale(mul(get(&ln.thr, i), le), w));
        }
    }
    if ln.depth[i] + 1 >= s.max_depth {
        ln.finish::<LIGHTS, _>(i, sc, stacks, out);
        return false;
    }
    let sp = sc.surface_on(&hit, face, mat);
    g.t[i] = hit.t;
    put(&mut g.ng, i, sp.ng);
    put(&mut g.ns, i, sp.ns);
    put(&mut g.albedo, i, sp.albedo);
    let rng = &mut ln.rng[i];
    g.has_ls[i] = false;
    if s.strategy != Strategy::Bsdf {
        let u = rng.next_f32();
        let uv = rng.next_2d();
        if let Some(ls) = sc.sample_emitter(u, uv) {
            g.has_ls[i] = true;
            put(&mut g.ls_p, i, ls.p);
            put(&mut g.ls_n, i, ls.n);
            g.ls_pdf[i] = ls.pdf_area;
            put(&mut g.ls_le, i, ls.le);
            g.ls_two[i] = ls.two_sided;
        }
    }
    // Point and directional lights, and one environment sample, per lane in the scalar
    // loop's code (their shadow rays are traced here, as there).
    if LIGHTS {
        g.delta[i] = [0.0; 3];
        g.env[i] = None;
    }
    if LIGHTS && (!sc.lights.is_empty() || sc.env.is_some()) {
        let thr = get(&ln.thr, i);
        let v = Vertex {
            p: add(org, scale(dir, hit.t)),
            wo,
            sp: &sp,
            bsdf: Bsdf::Diffuse,
        };
        if !sc.lights.is_empty() {
            g.delta[i] = mul(thr, delta_lights(sc, &v));
        }
        if sc.env.is_some() && s.strategy != Strategy::Bsdf {
            let u = rng.next_2d();
            let le = environment_nee(sc, &v, u, s.strategy == Strategy::Mis);
            g.env[i] = Some(mul(thr, le));
        }
    }
    // The BSDF sample's first number picks a lobe, which a diffuse surface does not need.
    let _ = rng.next_f32();
    let [a, b] = rng.next_2d();
    g.bsdf_uv[0][i] = a;
    g.bsdf_uv[1][i] = b;
    true
}
