//! The lane-parallel half of `path_lanes`' vertex (its scalar half is `visit`): next-event
//! estimation towards the gathered emitter samples, the diffuse BSDF sample, Russian
//! roulette and the next rays, on eight lanes with masks in place of branches.

use super::{Gather, Lanes, L};
use crate::bvh::{Slab, TraceStacks};
use crate::camera_sample::Sample;
use crate::lane_math::{
    add3, bits, cosine_hemisphere4, dot3, f4, f43, get, max3, mul3, offset4, power4, put, scale3,
    sel3, splat, store3, sub3, Lane, F3,
};
use crate::render_path::{PathSettings, Strategy};
use crate::render_scene::RenderScene;
use crate::sampling::scale;
use std::f32::consts::FRAC_1_PI;

/// The lane-parallel part of a vertex for the lanes in `go`: next-event estimation
/// towards the gathered emitter sample, the BSDF sample for the next segment, Russian
/// roulette, and the next ray's origin.
#[inline(always)]
pub(super) fn shade<const LIGHTS: bool, S: Slab, F: Lane>(
    sc: &RenderScene,
    s: &PathSettings,
    ln: &mut Lanes,
    g: &Gather,
    go: [bool; L],
    stacks: &mut TraceStacks<S>,
    out: &mut [Sample],
) {
    let zero = splat::<F>(0.0);
    let neg = splat::<F>(-1.0);
    let org = f43::<F>(&ln.org);
    let dir = f43::<F>(&ln.dir);
    let thr = f43::<F>(&ln.thr);
    let p = add3(org, scale3(dir, f4::<F>(&g.t)));
    let wo = scale3(dir, neg);
    let ng = f43::<F>(&g.ng);
    let ns = f43::<F>(&g.ns);
    let albedo = f43::<F>(&g.albedo);
    // `bsdf::sides`: the normals flipped to wo's side, the shading normal replaced by the
    // geometric one when wo is below its hemisphere; no lobe when wo grazes the surface.
    let co = dot3(ng, wo);
    let sides_ok = co.simd_ne(zero) & co.is_finite();
    let sgn = co.simd_lt(zero).select(neg, splat::<F>(1.0));
    let gside = scale3(ng, sgn);
    let n = scale3(ns, sgn);
    let n = sel3(dot3(n, wo).simd_le(splat::<F>(1e-4)), gside, n);

    // Next-event estimation (`radiance`'s emitter sample, MIS-weighted).
    let v = LaneVertex {
        p,
        thr,
        ng,
        n,
        gside,
        albedo,
        sides_ok,
    };
    let (o, seg_d, c, nee_bits) = emitter_nee4(sc, s.strategy == Strategy::Mis, g, &v);

    // BSDF sampling (`Bsdf::sample`, diffuse): a cosine-weighted direction about n.
    let uv = [f4::<F>(&g.bsdf_uv[0]), f4::<F>(&g.bsdf_uv[1])];
    let wi2 = cosine_hemisphere4(n, uv);
    let ci2 = dot3(n, wi2);
    let sampled = sides_ok & !(ci2.simd_le(zero) | dot3(gside, wi2).simd_le(zero));
    let sampled_bits = bits(sampled);
    let pdf2 = ci2 * splat::<F>(FRAC_1_PI);
    let thr2 = mul3(thr, albedo);
    let tmaxc = max3(thr2);
    let side2 = sel3(dot3(ng, wi2).simd_gt(zero), ng, scale3(ng, neg));
    let org2 = offset4(sc.eps, p, side2);

    // Lanes outside `go` are idle, so whole vectors are stored; the per-lane loop below
    // only decides which paths end and applies Russian roulette.
    store3(&mut ln.seg_o, o);
    store3(&mut ln.seg_d, seg_d);
    store3(&mut ln.nee_c, c);
    store3(&mut ln.thr, thr2);
    store3(&mut ln.org, org2);
    store3(&mut ln.dir, wi2);
    let pdf2 = pdf2.to_array();
    let tmaxc = tmaxc.to_array();
    for i in 0..L {
        if !go[i] {
            continue;
        }
        ln.pending[i] = true;
        ln.nee[i] = nee_bits & (1 << i) != 0;
        if LIGHTS {
            ln.delta[i] = g.delta[i];
            ln.env[i] = g.env[i];
        }
        if sampled_bits & (1 << i) == 0 {
            ln.finish::<LIGHTS, _>(i, sc, stacks, out);
            continue;
        }
        ln.prev_pdf[i] = pdf2[i];
        ln.depth[i] += 1;
        let tm = tmaxc[i];
        if ln.depth[i] >= s.rr_depth {
            // The scalar loop's (tm eta eta).min(0.95) with eta = 1 (exact).
            let q = tm.min(0.95);
            if ln.rng[i].next_f32() >= q {
                ln.finish::<LIGHTS, _>(i, sc, stacks, out);
                continue;
            }
            let t = scale(get(&ln.thr, i), 1.0 / q);
            put(&mut ln.thr, i, t);
        }
        if tm <= 0.0 || !tm.is_finite() {
            ln.finish::<LIGHTS, _>(i, sc, stacks, out);
            continue;
        }
        ln.tmax[i] = f32::INFINITY;
    }
}

/// A diffuse path vertex in eight lanes: the point, the path throughput, the geometric
/// normal, the normals flipped to the viewer's side (shading `n`, geometric `gside`), the
/// albedo, and which lanes have a valid side (`bsdf::sides`).
struct LaneVertex<F> {
    p: F3<F>,
    thr: F3<F>,
    ng: F3<F>,
    n: F3<F>,
    gside: F3<F>,
    albedo: F3<F>,
    sides_ok: F,
}

/// `render_path`'s `area_emitter_nee` in eight lanes, for the emitter samples gathered in
/// `g`: the shadow rays' origins and directions, their contributions when unblocked, and
/// the lanes (bits) whose sample contributes.
#[inline(always)]
fn emitter_nee4<F: Lane>(
    sc: &RenderScene,
    mis: bool,
    g: &Gather,
    v: &LaneVertex<F>,
) -> (F3<F>, F3<F>, F3<F>, u32) {
    let zero = splat::<F>(0.0);
    let neg = splat::<F>(-1.0);
    let (p, ng, n) = (v.p, v.ng, v.n);
    let ls_p = f43::<F>(&g.ls_p);
    let ls_n = f43::<F>(&g.ls_n);
    let has_ls = F::from_array(g.has_ls.map(|b| if b { f32::from_bits(!0) } else { 0.0 }));
    let two = F::from_array(g.ls_two.map(|b| if b { f32::from_bits(!0) } else { 0.0 }));
    let dv = sub3(ls_p, p);
    let dist2 = dot3(dv, dv);
    let dist = dist2.sqrt();
    let wi = scale3(dv, splat::<F>(1.0) / dist);
    let front = two | dot3(ls_n, scale3(wi, neg)).simd_gt(zero);
    let le = sel3(front, f43::<F>(&g.ls_le), [zero; 3]);
    let cos_l = dot3(ls_n, wi).abs();
    // `Bsdf::eval_pdf` for the diffuse lobe.
    let ci = dot3(n, wi);
    let lit = v.sides_ok & !(ci.simd_le(zero) | dot3(v.gside, wi).simd_le(zero));
    let cpi = ci * splat::<F>(FRAC_1_PI);
    let f = sel3(lit, scale3(v.albedo, cpi), [zero; 3]);
    let bsdf_pdf = lit.select(cpi, zero);
    let nee_ok = has_ls
        & dist.simd_gt(zero)
        & max3(le).simd_gt(zero)
        & cos_l.simd_gt(zero)
        & max3(f).simd_gt(zero);
    let side = sel3(dot3(ng, wi).simd_gt(zero), ng, scale3(ng, neg));
    let o = offset4(sc.eps, p, side);
    let p_light = f4::<F>(&g.ls_pdf) * dist2 / cos_l;
    let w = if mis {
        power4(p_light, bsdf_pdf)
    } else {
        splat::<F>(1.0)
    };
    let c = scale3(mul3(v.thr, mul3(f, le)), w / p_light);
    (o, sub3(ls_p, o), c, bits(nee_ok))
}
