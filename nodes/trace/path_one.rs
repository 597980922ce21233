//! `render_path`'s estimator over a batch of pixel samples one path at a time
//! (`render_path::radiance`): the loop for scenes the lane one does not take (a mirror,
//! glass or GGX material), in a baseline build and, chosen at run time, one for x86-64-v3.

#[cfg(target_arch = "x86_64")]
use super::bvh::Avx;
use super::bvh::{Slab, TraceStacks};
use super::camera_sample::{Batch, Sample, Starts};
use super::render_path::radiance;

/// The batch's pixel samples traced one path at a time (`radiance`), their radiance and
/// film positions in `jobs`' order: the loop for scenes the lane one does not take
/// (`path_lanes::handles`). Where `v3` and the CPU has x86-64-v3 it runs a build of itself
/// for that (`radiance_samples_avx2`: walks inlined, node boxes on 256-bit registers, the
/// same bits).
pub fn radiance_samples(b: Batch, stacks: &mut TraceStacks, v3: bool) -> Vec<Sample> {
    #[cfg(target_arch = "x86_64")]
    if let Some(avx) = Avx::detect_v3().filter(|_| v3) {
        // SAFETY: `radiance_samples_avx2` needs exactly the features `detect_v3` found.
        return unsafe { radiance_samples_avx2(b, avx) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = v3;
    samples_body(b, stacks)
}

/// `radiance_samples` built for x86-64-v3, chosen at run time (as `path_lanes::trace_avx2`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
fn radiance_samples_avx2(b: Batch, avx: Avx) -> Vec<Sample> {
    samples_body(b, &mut TraceStacks::with_slab(avx))
}

/// `radiance_samples`' loop, inlined into both builds.
#[inline(always)]
fn samples_body<S: Slab>(b: Batch, stacks: &mut TraceStacks<S>) -> Vec<Sample> {
    let (sc, cam) = (b.sc, b.cam);
    // A loop, not a closure: a closure is not built for the caller's target features
    // unless LLVM inlines it, and this one is too large to be.
    let mut out = Vec::with_capacity(b.jobs.len());
    for mut cs in Starts::<wide::f32x8>::new(b) {
        let c = radiance(
            sc,
            cam.eye,
            cs.dir,
            cam.far,
            cs.hit,
            &mut cs.rng,
            b.s,
            stacks,
        );
        out.push(Sample {
            c,
            fx: cs.fx,
            fy: cs.fy,
        });
    }
    out
}
