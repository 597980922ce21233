//! Random numbers and sampling routines shared by the ray and path tracers: a PCG32
//! generator with deterministic per-pixel seeding, cosine-weighted hemisphere sampling,
//! uniform triangle sampling, an orthonormal frame and the power heuristic for multiple
//! importance sampling. The f32 vector helpers (`V3`, in `v3.rs`) are re-exported here.

pub use cgnodes_api::rng::{splitmix64, Pcg32};
pub use cgnodes_geometry::distribution::Distribution1D;
pub use cgnodes_geometry::v3::*;

/// An orthonormal basis around unit normal `n` (Duff et al. 2017, "Building an Orthonormal
/// Basis, Revisited", Listing 3). Returns (tangent, bitangent).
#[inline(always)]
pub fn onb(n: V3) -> (V3, V3) {
    let sign = 1.0f32.copysign(n[2]);
    let a = -1.0 / (sign + n[2]);
    let b = n[0] * n[1] * a;
    (
        [1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]],
        [b, sign + n[1] * n[1] * a, -n[1]],
    )
}

/// Cosine-weighted direction about unit normal `n` via Malley's method (concentric disk
/// mapping of Shirley & Chiu 1997, lifted to the hemisphere). pdf = cos(theta) / pi.
#[inline(always)]
pub fn cosine_hemisphere(n: V3, u: [f32; 2]) -> V3 {
    let (t, b) = onb(n);
    let ox = 2.0 * u[0] - 1.0;
    let oy = 2.0 * u[1] - 1.0;
    // phi = pi/4 (oy/ox), or pi/2 - pi/4 (ox/oy), so sin and cos are only needed on
    // [-pi/4, pi/4] (the second case swaps them), where short Taylor series are exact to
    // f32 precision and cheaper than the library's `sin_cos`.
    let (x, y) = if ox == 0.0 && oy == 0.0 {
        (0.0, 0.0)
    } else if ox.abs() > oy.abs() {
        let (s, c) = sin_cos_quarter(std::f32::consts::FRAC_PI_4 * (oy / ox));
        (ox * c, ox * s)
    } else {
        let (s, c) = sin_cos_quarter(std::f32::consts::FRAC_PI_4 * (ox / oy));
        (oy * s, oy * c)
    };
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    add(add(scale(t, x), scale(b, y)), scale(n, z))
}

/// `(sin a, cos a)` for `|a| <= pi/4`: Taylor series to the a^7 and a^8 terms, whose
/// truncation errors there are below 3.2e-7 and 2.5e-8 (about 2 and 0.2 ulp of 0.7).
#[inline(always)]
pub fn sin_cos_quarter(a: f32) -> (f32, f32) {
    let a2 = a * a;
    let r = SERIES_RECIPROCALS;
    let s = a * (1.0 - a2 * r[0] * (1.0 - a2 * r[1] * (1.0 - a2 * r[2])));
    let c = 1.0 - a2 * 0.5 * (1.0 - a2 * r[3] * (1.0 - a2 * r[4] * (1.0 - a2 * r[5])));
    (s, c)
}

/// The series' divisors of `sin_cos_quarter` as reciprocals (1/6, 1/20, 1/42 for the sine,
/// 1/12, 1/30, 1/56 for the cosine): a product each instead of a division, which costs
/// about as much as the rest of the series.
pub(crate) const SERIES_RECIPROCALS: [f32; 6] = [
    1.0 / 6.0,
    1.0 / 20.0,
    1.0 / 42.0,
    1.0 / 12.0,
    1.0 / 30.0,
    1.0 / 56.0,
];

/// Uniform barycentrics on a triangle (Heitz 2019, "A Low-Distortion Map Between Triangle
/// and Square"). Returns (b1, b2); the point is `(1-b1-b2) a + b1 b + b2 c`.
#[inline(always)]
pub fn uniform_triangle(u: [f32; 2]) -> (f32, f32) {
    let (mut b0, mut b1);
    if u[0] < u[1] {
        b0 = u[0] / 2.0;
        b1 = u[1] - b0;
    } else {
        b1 = u[1] / 2.0;
        b0 = u[0] - b1;
    }
    b0 = b0.clamp(0.0, 1.0);
    b1 = b1.clamp(0.0, 1.0 - b0);
    (b0, b1)
}

/// The power heuristic with beta = 2 (Veach 1997, eq. 9.13), for one sample of each of two
/// strategies: the weight of the strategy with density `pa` against one with density `pb`.
#[inline(always)]
pub fn power_heuristic(pa: f32, pb: f32) -> f32 {
    let a = pa * pa;
    let b = pb * pb;
    if a + b > 0.0 && a.is_finite() {
        a / (a + b)
    } else if a.is_infinite() {
        1.0
    } else {
        0.0
    }
}

/// One bin of an `AliasTable`: keep this index when the remapped number is below `q`,
/// else take `alias`.
#[derive(Clone, Copy, Debug)]
pub struct AliasBin {
    /// Probability of keeping the bin's own index.
    pub q: f32,
    /// The index taken otherwise.
    pub alias: u32,
}

/// A discrete distribution sampled in constant time by the alias method (Walker 1977,
/// built as in Vose 1991; pbrt-v4 section A.1): one bin per index, so a sample reads one
/// bin instead of walking a binary search (docs/path_tracing.md, "How it runs").
#[derive(Clone, Debug, Default)]
pub struct AliasTable {
    bins: Vec<AliasBin>,
}

impl AliasTable {
    /// The table for the distribution proportional to `weights` (negative or non-finite
    /// weights count as zero). Empty when no weight is positive.
    pub fn new(weights: &[f64]) -> AliasTable {
        if weights.len() >= u32::MAX as usize {
            return AliasTable::default();
        }
        let w: Vec<f64> = weights
            .iter()
            .map(|&w| if w.is_finite() && w > 0.0 { w } else { 0.0 })
            .collect();
        let total: f64 = w.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return AliasTable::default();
        }
        let n = w.len();
        // Scaled probabilities p_i n: a bin below 1 takes its remainder from one above.
        let mut p: Vec<f64> = w.iter().map(|x| x / total * n as f64).collect();
        let mut bins: Vec<AliasBin> = (0..n)
            .map(|i| AliasBin {
                q: 1.0,
                alias: i as u32,
            })
            .collect();
        let (mut under, mut over): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| p[i] < 1.0);
        while let (Some(&u), Some(&o)) = (under.last(), over.last()) {
            under.pop();
            over.pop();
            bins[u] = AliasBin {
                q: p[u] as f32,
                alias: o as u32,
            };
            p[o] -= 1.0 - p[u];
            if p[o] < 1.0 {
                under.push(o);
            } else {
                over.push(o);
            }
        }
        // What is left holds (up to round-off) exactly one bin's worth: keep it. A
        // zero-weight index left here by round-off would be drawn, so it goes to the
        // largest weight instead.
        let big = (0..n).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap_or(0);
        for i in under.into_iter().chain(over) {
            bins[i] = if w[i] > 0.0 {
                AliasBin {
                    q: 1.0,
                    alias: i as u32,
                }
            } else {
                AliasBin {
                    q: 0.0,
                    alias: big as u32,
                }
            };
        }
        AliasTable { bins }
    }

    /// Whether nothing can be sampled.
    pub fn is_empty(&self) -> bool {
        self.bins.is_empty()
    }

    /// An index drawn from uniform `u` in [0, 1): `u n` picks a bin, its fraction decides
    /// between the bin's index and its alias. Panics when the table is empty.
    #[inline(always)]
    pub fn sample(&self, u: f32) -> usize {
        let n = self.bins.len();
        let x = u * n as f32;
        let k = (x as u32).min(n as u32 - 1) as usize;
        let b = self.bins[k];
        if x - (k as f32) < b.q {
            k
        } else {
            b.alias as usize
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pcg32_matches_reference_stream() {
        // pcg32-demo (pcg32_srandom_r(42, 54)) prints these first outputs.
        let mut r = Pcg32::new(42, 54);
        let want = [
            0xa15c02b7u32,
            0x7b47f409,
            0xba1d3330,
            0x83d2f293,
            0xbfa4784b,
        ];
        for w in want {
            assert_eq!(r.next_u32(), w);
        }
    }

    #[test]
    fn quarter_sin_cos_matches_the_library() {
        // The series against f64 sin and cos on [-pi/4, pi/4], ends included.
        let q = std::f64::consts::FRAC_PI_4;
        for i in 0..=10_000 {
            let a = (-q + 2.0 * q * i as f64 / 10_000.0) as f32;
            let (s, c) = sin_cos_quarter(a);
            assert!((s as f64 - (a as f64).sin()).abs() < 4e-7, "sin {a}: {s}");
            assert!((c as f64 - (a as f64).cos()).abs() < 1.5e-7, "cos {a}: {c}");
        }
    }

    #[test]
    fn cosine_hemisphere_has_cosine_mean() {
        // E[cos] under pdf cos/pi is 2/3; E[cos^2] is 1/2.
        let n = normalize([0.3, -0.5, 0.8]);
        let mut r = Pcg32::new(1, 2);
        let (mut m1, mut m2) = (0.0f64, 0.0f64);
        let k = 200_000;
        for _ in 0..k {
            let d = cosine_hemisphere(n, r.next_2d());
            assert!((length(d) - 1.0).abs() < 1e-4);
            let c = dot(d, n) as f64;
            assert!(c >= -1e-6);
            m1 += c;
            m2 += c * c;
        }
        assert!((m1 / k as f64 - 2.0 / 3.0).abs() < 3e-3);
        assert!((m2 / k as f64 - 0.5).abs() < 3e-3);
    }

    #[test]
    fn uniform_triangle_is_uniform() {
        let mut r = Pcg32::new(3, 4);
        let k = 100_000;
        let (mut s0, mut s1, mut inside) = (0.0f64, 0.0f64, 0);
        for _ in 0..k {
            let (b1, b2) = uniform_triangle(r.next_2d());
            s0 += b1 as f64;
            s1 += b2 as f64;
            // Fraction in the sub-triangle b1 + b2 < 1/2 should be 1/4.
            if b1 + b2 < 0.5 {
                inside += 1;
            }
        }
        assert!((s0 / k as f64 - 1.0 / 3.0).abs() < 5e-3);
        assert!((s1 / k as f64 - 1.0 / 3.0).abs() < 5e-3);
        assert!((inside as f64 / k as f64 - 0.25).abs() < 5e-3);
    }

    #[test]
    fn alias_table_draws_each_index_with_its_probability() {
        // Weights with a zero, one dominant index, and many small ones.
        let mut w = vec![0.0, 5.0, 1.0, 0.0, 2.5, 1e-3];
        w.extend((0..20).map(|i| 0.1 + i as f64 * 0.05));
        let total: f64 = w.iter().sum();
        let t = AliasTable::new(&w);
        let k = 2_000_000;
        let mut count = vec![0usize; w.len()];
        let mut r = Pcg32::new(7, 9);
        for _ in 0..k {
            count[t.sample(r.next_f32())] += 1;
        }
        for (i, (&c, &wi)) in count.iter().zip(&w).enumerate() {
            let p = wi / total;
            if wi == 0.0 {
                assert_eq!(c, 0, "index {i} has no weight");
            }
            // Within 5 standard deviations of the binomial count.
            let sd = (k as f64 * p * (1.0 - p)).sqrt();
            assert!(
                (c as f64 - k as f64 * p).abs() <= 5.0 * sd + 1.0,
                "index {i}: {c} draws, expected {}",
                k as f64 * p
            );
        }
        // The last representable number below 1 stays in range.
        assert!(t.sample(1.0 - f32::EPSILON / 2.0) < w.len());
        assert!(AliasTable::new(&[0.0, -1.0, f64::NAN]).is_empty());
        assert_eq!(AliasTable::new(&[3.0]).sample(0.7), 0);
    }

    #[test]
    fn distribution_samples_proportionally() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]);
        assert_eq!(d.sample(0.1), 0);
        assert_eq!(d.sample(0.25), 2);
        assert_eq!(d.sample(0.99), 2);
        assert!((d.pmf(2) - 0.75).abs() < 1e-6);
        assert_eq!(d.pmf(1), 0.0);
    }

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        let w = power_heuristic(2.0, 3.0) + power_heuristic(3.0, 2.0);
        assert!((w - 1.0).abs() < 1e-6);
    }
}
