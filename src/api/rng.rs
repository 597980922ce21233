//! Deterministic random numbers for nodes: one generator for the whole project, so that
//! results are reproducible from a seed whatever the thread count, and no node carries its
//! own copy of the LCG constants.

/// PCG32 (O'Neill 2014, "PCG: A Family of Simple Fast Space-Efficient Statistically Good
/// Algorithms for Random Number Generation"): 64-bit LCG state, XSH-RR output.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    const MULT: u64 = 6364136223846793005;

    /// The generator with initial state `seed` on stream `stream` (pcg32_srandom_r).
    pub fn new(seed: u64, stream: u64) -> Pcg32 {
        let mut r = Pcg32 {
            state: 0,
            inc: (stream << 1) | 1,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }

    /// The deterministic generator for one pixel sample: the pixel index and the user seed
    /// are hashed into the initial state, the sample index selects the stream, so any
    /// sample of any pixel can be reproduced on its own, whatever the tiling or thread count.
    pub fn for_sample(pixel: u64, sample: u64, seed: u64) -> Pcg32 {
        Pcg32::new(
            splitmix64(pixel ^ splitmix64(seed)),
            splitmix64(sample.wrapping_add(seed.rotate_left(32))),
        )
    }

    /// `for_sample` for `N` pixel samples at once, each generator then advanced past its
    /// first two numbers (`next_2d`), which are returned beside it (first numbers, then
    /// second ones): the same integers as one sample at a time, computed in loops over
    /// arrays that the compiler turns into SIMD (the path tracer starts eight paths
    /// together).
    #[inline(always)]
    pub fn for_samples_2d<const N: usize>(
        pixel: &[u64; N],
        sample: &[u64; N],
        seed: u64,
    ) -> ([Pcg32; N], [[f32; N]; 2]) {
        let (mix_seed, rot_seed) = (splitmix64(seed), seed.rotate_left(32));
        let mut inc = [0u64; N];
        let mut state = [0u64; N];
        for i in 0..N {
            inc[i] = (splitmix64(sample[i].wrapping_add(rot_seed)) << 1) | 1;
        }
        // `new`: the first step from state 0 leaves `inc`; add the seed; step again.
        for i in 0..N {
            let s = inc[i].wrapping_add(splitmix64(pixel[i] ^ mix_seed));
            state[i] = s.wrapping_mul(Self::MULT).wrapping_add(inc[i]);
        }
        let mut u = [[0.0f32; N]; 2];
        for uk in &mut u {
            for i in 0..N {
                let old = state[i];
                state[i] = old.wrapping_mul(Self::MULT).wrapping_add(inc[i]);
                uk[i] = unit_f32(Self::output(old));
            }
        }
        let r = std::array::from_fn(|i| Pcg32 {
            state: state[i],
            inc: inc[i],
        });
        (r, u)
    }

    /// PCG's output function (XSH RR) of the state before a step.
    #[inline(always)]
    fn output(old: u64) -> u32 {
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// The next 32 random bits.
    #[inline(always)]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MULT).wrapping_add(self.inc);
        Self::output(old)
    }

    /// A uniform float in [0, 1) (24 random mantissa bits).
    #[inline(always)]
    pub fn next_f32(&mut self) -> f32 {
        unit_f32(self.next_u32())
    }

    /// Two uniform floats in [0, 1).
    #[inline(always)]
    pub fn next_2d(&mut self) -> [f32; 2] {
        [self.next_f32(), self.next_f32()]
    }
}

/// SplitMix64 finaliser (Steele et al. 2014), used as an integer hash for seeding.
#[inline]
pub fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E3779B97F4A7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
    z ^ (z >> 31)
}

/// A uniform float in [0, 1) from a 64-bit LCG state advanced in place (Knuth's MMIX
/// constants, the same multiplier as PCG32's state); for tests and simple jitter where a
/// full PCG32 stream is not needed.
#[inline]
pub fn lcg_next(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*state >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A uniform float in [0, 1) from 32 random bits (their top 24 as the mantissa).
#[inline(always)]
fn unit_f32(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn batch_starts_are_the_single_ones() {
        let seeds = [0u64, 1, 7, u64::MAX, 0x9E37_79B9_7F4A_7C15];
        for seed in seeds {
            let pixel: [u64; 8] = std::array::from_fn(|i| (i as u64) * 977 + seed % 13);
            let sample: [u64; 8] = std::array::from_fn(|i| u64::MAX - i as u64 * 3);
            let (r, u) = Pcg32::for_samples_2d(&pixel, &sample, seed);
            for i in 0..8 {
                let mut one = Pcg32::for_sample(pixel[i], sample[i], seed);
                let [a, b] = one.next_2d();
                assert_eq!(
                    (a.to_bits(), b.to_bits()),
                    (u[0][i].to_bits(), u[1][i].to_bits())
                );
                let mut batch = r[i].clone();
                for _ in 0..5 {
                    assert_eq!(one.next_u32(), batch.next_u32());
                }
            }
        }
    }
}
