//! One path of `render_path`'s estimator as a resumable state (`PathState`): it names the
//! rays it needs next (the next segment, and the shadow ray of the direct light estimated at
//! the previous vertex), and `advance` takes their answers and shades the hit. Written this
//! way so that the independent rays of a path (its shadow ray and its next segment) and of
//! two paths (`radiance2`) can be traced in one interleaved traversal
//! (`Bvh::intersect_occluded`, `Bvh::trace_many`), which hides part of the latency of each
//! ray's dependent chain of node loads (docs/path_tracing.md, fourth round). The estimator
//! itself (NEE, BSDF sampling, MIS, Russian roulette) is the one described in
//! `render_path.rs`; every path draws the same random numbers and adds its estimates in the
//! same order as when its rays were traced one at a time, so images are bit for bit the
//! same.

use super::bvh::{Hit, Segment};
use super::direct::{delta_lights, environment_nee, Vertex};
use super::render_path::{PathSettings, Strategy};
use super::render_scene::RenderScene;
use super::sampling::{add, dot, max_comp, mul, power_heuristic, scale, sub, Pcg32, V3};

/// Direct light estimated at a path vertex whose shadow ray has not been traced yet: it is
/// traced together with the next segment's ray and added to the path's radiance before
/// anything the next segment finds, in the order the estimates were made, so the sums are
/// bit for bit those of tracing the shadow ray at once.
#[derive(Clone, Copy, Debug)]
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
}

/// A path being traced: its throughput, the radiance gathered so far, the segment to trace
/// next and the direct light waiting for its shadow ray.
pub struct PathState<'a> {
    rng: &'a mut Pcg32,
    l: V3,
    thr: V3,
    eta: f32,
    prev_pdf: f32,
    prev_delta: bool,
    depth: u32,
    ray: Segment,
    pending: Option<Deferred>,
}

impl<'a> PathState<'a> {
    /// A path starting with the ray `org + t dir`, `t < tmax`, drawing from `rng`.
    pub fn new(org: V3, dir: V3, tmax: f32, rng: &'a mut Pcg32) -> PathState<'a> {
        PathState {
            rng,
            l: [0.0; 3],
            thr: [1.0; 3],
            eta: 1.0,
            prev_pdf: 0.0,
            prev_delta: true,
            depth: 0,
            ray: (org, dir, tmax),
            pending: None,
        }
    }

    /// The rays to trace next: the segment (closest hit) and, when the previous vertex
    /// estimated light from an area emitter, that estimate's shadow ray (any hit).
    #[inline]
    pub fn rays(&self) -> (Segment, Option<Segment>) {
        (self.ray, self.pending.and_then(|d| d.nee.map(|n| n.0)))
    }

    /// The radiance of the finished path: traces the last shadow ray when the path ended
    /// after estimating direct light.
    pub fn finish(self, sc: &RenderScene) -> V3 {
        match self.pending {
            Some(d) => {
                let blocked = d.nee.is_some_and(|((o, w, t), _)| sc.bvh.occluded(o, w, t));
                d.add_to(self.l, blocked)
            }
            None => self.l,
        }
    }

    /// Takes the answers for `rays()` (the segment's closest hit, whether the shadow ray is
    /// blocked; false when there was none), adds the pending direct light, shades the hit
    /// and samples the next segment. Returns false when the path has ended (then `finish`).
    pub fn advance(&mut self, sc: &RenderScene, s: &PathSettings, hit: Option<Hit>, blocked: bool) -> bool {
        if let Some(d) = self.pending.take() {
            self.l = d.add_to(self.l, blocked);
        }
        let (org, dir, _) = self.ray;
        let (thr, depth) = (self.thr, self.depth);
        let Some(hit) = hit else {
            // The ray escapes: the environment's radiance, weighted like an emitter hit.
            if let Some(env) = &sc.env {
                let w = if depth == 0 || self.prev_delta {
                    1.0
                } else {
                    match s.strategy {
                        Strategy::Bsdf => 1.0,
                        Strategy::Nee => 0.0,
                        Strategy::Mis => power_heuristic(self.prev_pdf, env.pdf(dir)),
                    }
                };
                self.l = add(self.l, scale(mul(thr, env.eval(dir)), w));
            }
            return false;
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
                let w = if depth == 0 || self.prev_delta {
                    1.0
                } else {
                    match s.strategy {
                        Strategy::Bsdf => 1.0,
                        Strategy::Nee => 0.0,
                        Strategy::Mis => {
                            let cos_l = dot(ng, wo).abs();
                            let p_light = sc.light_pdf_area[tri as usize] * hit.t * hit.t / cos_l;
                            power_heuristic(self.prev_pdf, p_light)
                        }
                    }
                };
                self.l = add(self.l, scale(mul(thr, le), w));
            }
        }
        if depth + 1 >= s.max_depth {
            return false;
        }
        let bsdf = mat.bsdf;
        let sp = sc.surface(&hit);
        let (ns, albedo) = (sp.ns, sp.albedo);
        let rng = &mut *self.rng;
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
                            let f = bsdf.eval(albedo, ng, ns, wo, wi);
                            if max_comp(f) > 0.0 {
                                let side = if dot(ng, wi) > 0.0 {
                                    ng
                                } else {
                                    scale(ng, -1.0)
                                };
                                let o = sc.offset(p, side);
                                let p_light = ls.pdf_area * dist2 / cos_l;
                                let w = if s.strategy == Strategy::Mis {
                                    power_heuristic(p_light, bsdf.pdf(ng, ns, wo, wi))
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
            d.delta = mul(thr, delta_lights(sc, &v));
            if sc.env.is_some() && s.strategy != Strategy::Bsdf {
                let u = rng.next_2d();
                let le = environment_nee(sc, &v, u, s.strategy == Strategy::Mis);
                d.env = Some(mul(thr, le));
            }
            self.pending = Some(d);
        }
        // BSDF sampling for the next segment.
        let u = rng.next_f32();
        let uv = rng.next_2d();
        let Some(bs) = bsdf.sample(albedo, ng, ns, wo, u, uv) else {
            return false;
        };
        let mut thr = mul(thr, bs.weight);
        self.eta *= bs.eta;
        self.prev_pdf = bs.pdf;
        self.prev_delta = bs.delta;
        self.depth += 1;
        // Russian roulette (Arvo & Kirk 1990), as Mitsuba 3 does it.
        let tmaxc = max_comp(thr);
        if self.depth >= s.rr_depth {
            let q = (tmaxc * self.eta * self.eta).min(0.95);
            if rng.next_f32() >= q {
                return false;
            }
            thr = scale(thr, 1.0 / q);
        }
        self.thr = thr;
        if tmaxc <= 0.0 || !tmaxc.is_finite() {
            return false;
        }
        let side = if dot(ng, bs.wi) > 0.0 {
            ng
        } else {
            scale(ng, -1.0)
        };
        self.ray = (sc.offset(p, side), bs.wi, f32::INFINITY);
        true
    }

    /// Traces `rays()` (interleaved when there are two) and advances.
    #[inline]
    fn step(&mut self, sc: &RenderScene, s: &PathSettings) -> bool {
        let (hit, blocked) = match self.rays() {
            (r, Some(shadow)) => sc.bvh.intersect_occluded(r, shadow),
            (r, None) => (sc.intersect(r.0, r.1, r.2), false),
        };
        self.advance(sc, s, hit, blocked)
    }
}

/// Radiance arriving at `org` from direction `-dir` (unit `dir`), estimated with one path.
pub fn radiance(
    sc: &RenderScene,
    org: V3,
    dir: V3,
    tmax: f32,
    rng: &mut Pcg32,
    s: &PathSettings,
) -> V3 {
    let mut p = PathState::new(org, dir, tmax, rng);
    while p.step(sc, s) {}
    p.finish(sc)
}

/// Two paths estimated in lockstep: at every step the rays both need (up to four: each
/// one's segment and shadow ray) are traced in one interleaved traversal; once one path
/// has ended the other goes on alone. The same radiance, bit for bit, as two calls of
/// `radiance`.
pub fn radiance2(sc: &RenderScene, a: PathState, b: PathState, s: &PathSettings) -> [V3; 2] {
    let (mut a, mut b) = (a, b);
    loop {
        let (ra, sa) = a.rays();
        let (rb, sb) = b.rays();
        let mut segs = [(ra, false); 4];
        let mut n = 1;
        let ia = sa.map(|r| {
            segs[n] = (r, true);
            n += 1;
            n - 1
        });
        let ib = n;
        segs[n] = (rb, false);
        n += 1;
        let jb = sb.map(|r| {
            segs[n] = (r, true);
            n += 1;
            n - 1
        });
        let mut out = [None; 4];
        sc.bvh.trace_many(&segs[..n], &mut out);
        let go_a = a.advance(sc, s, out[0], ia.is_some_and(|i| out[i].is_some()));
        let go_b = b.advance(sc, s, out[ib], jb.is_some_and(|j| out[j].is_some()));
        match (go_a, go_b) {
            (true, true) => {}
            (true, false) => {
                while a.step(sc, s) {}
                break;
            }
            (false, true) => {
                while b.step(sc, s) {}
                break;
            }
            (false, false) => break,
        }
    }
    [a.finish(sc), b.finish(sc)]
}
