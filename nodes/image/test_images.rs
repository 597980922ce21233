//! Test images shared by the crate's unit tests (one generator instead of a copy per module).

use cgnodes_api::types::Image;

/// A deterministic opaque `w x h` image: per channel `c` a wave
/// `0.5 + 0.3 sin(fx x + c + fy y)` plus `noise` times a uniform value in [0, 1) from a
/// 64-bit linear congruential generator (Knuth's MMIX constants) seeded by `seed`.
pub(crate) fn waves(w: u32, h: u32, seed: u64, [fx, fy]: [f32; 2], noise: f32) -> Image {
    let step = |s: u64| {
        s.wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407)
    };
    let mut s = step(seed);
    let mut img = Image::new(w, h, [0.0, 0.0, 0.0, 1.0]);
    for y in 0..h {
        for x in 0..w {
            let mut p = [0.0f32, 0.0, 0.0, 1.0];
            for (c, v) in p.iter_mut().take(3).enumerate() {
                s = step(s);
                let u = (s >> 40) as f32 / (1u64 << 24) as f32;
                *v = 0.5 + 0.3 * ((x as f32 * fx + c as f32) + y as f32 * fy).sin() + noise * u;
            }
            img.set(x, y, p);
        }
    }
    img
}
