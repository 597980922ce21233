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

    /// The next 32 random bits.
    #[inline(always)]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// A uniform float in [0, 1) (24 random mantissa bits).
    #[inline(always)]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
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
