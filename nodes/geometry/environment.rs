//! The environment light of the tracers: radiance arriving from infinitely far away, an
//! equirectangular image (or a constant colour) looked up per texel, and importance
//! sampling of directions by luminance with a 2-D piecewise-constant distribution over the
//! image (PBRT 3, section 13.6.7 for the distribution, section 14.2.4 for the infinite
//! area light): a row by the marginal over rows, then a column by that row's conditional,
//! each texel weighted by its luminance times sin(theta), the area of its band on the
//! sphere. The density in the image's unit square converts to solid angle by dividing by
//! the Jacobian 2 pi^2 sin(theta).
//!
//! Directions: row 0 is straight up (+y, theta = 0), the image centre looks along -z, and
//! u grows towards +x: `d = (sin t sin p, cos t, -sin t cos p)` with `t = pi v`,
//! `p = 2 pi (u - 1/2)`; `rotation` turns the environment counter-clockwise about +y
//! (seen from above). The lookup is the texel's value (nearest), so the sampling density
//! is exactly proportional to the luminance times sin(theta) of what is looked up.

use crate::distribution::Distribution1D;
use crate::v3::{luminance, V3};
use cgnodes_api::types::{Image, Light};
use std::f32::consts::PI;

/// A constant sky is sampled as an image of this size (so the sin(theta) weights still
/// spread samples evenly over the sphere).
const CONST_W: usize = 32;
const CONST_H: usize = 16;

/// An environment ready for lookups and sampling.
#[derive(Clone, Debug)]
pub struct Environment {
    w: usize,
    h: usize,
    /// Radiance per texel (colour and intensity applied), row 0 at the top.
    px: Vec<V3>,
    /// cos and sin of the rotation about +y.
    rot: (f32, f32),
    /// Marginal distribution over rows.
    rows: Distribution1D,
    /// Conditional distribution over columns, per row.
    cols: Vec<Distribution1D>,
    /// Mean radiance over the sphere (solid-angle weighted).
    mean: V3,
}

/// A sampled direction towards the environment.
#[derive(Clone, Copy, Debug)]
pub struct EnvSample {
    /// Unit world direction (from the surface towards the sky).
    pub wi: V3,
    /// Radiance arriving along `-wi`.
    pub le: V3,
    /// Solid-angle density.
    pub pdf: f32,
}

impl Environment {
    /// The first environment light of `lights`, if any (later ones are ignored).
    pub fn from_lights(lights: &[Light]) -> Option<Environment> {
        lights.iter().find_map(|l| match l {
            Light::Environment {
                image,
                color,
                intensity,
                rotation_deg,
            } => {
                let k = color.map(|c| (c * intensity) as f32);
                Some(Environment::new(image.as_deref(), k, *rotation_deg as f32))
            }
            _ => None,
        })
    }

    /// An environment of radiance `k` times `image` (or `k` alone), rotated by
    /// `rotation_deg` about +y. Negative or non-finite texels count as zero.
    pub fn new(image: Option<&Image>, k: V3, rotation_deg: f32) -> Environment {
        let clean = |c: f32| if c.is_finite() { c.max(0.0) } else { 0.0 };
        let (w, h, px) = match image {
            Some(img) if img.width > 0 && img.pixels.len() == (img.width * img.height) as usize => {
                let px = img
                    .pixels
                    .iter()
                    .map(|p| [clean(p[0] * k[0]), clean(p[1] * k[1]), clean(p[2] * k[2])])
                    .collect();
                (img.width as usize, img.height as usize, px)
            }
            _ => (CONST_W, CONST_H, vec![k.map(clean); CONST_W * CONST_H]),
        };
        let mut cols = Vec::with_capacity(h);
        let mut row_w = Vec::with_capacity(h);
        let mut mean = [0.0f64; 3];
        let mut wsum = 0.0f64;
        for y in 0..h {
            let s = (PI * (y as f32 + 0.5) / h as f32).sin() as f64;
            let lw: Vec<f64> = px[y * w..(y + 1) * w]
                .iter()
                .map(|c| luminance(*c) as f64 * s)
                .collect();
            for c in &px[y * w..(y + 1) * w] {
                for k in 0..3 {
                    mean[k] += c[k] as f64 * s;
                }
                wsum += s;
            }
            let d = Distribution1D::new(&lw);
            row_w.push(d.total());
            cols.push(d);
        }
        let r = rotation_deg.to_radians();
        Environment {
            w,
            h,
            px,
            rot: (r.cos(), r.sin()),
            rows: Distribution1D::new(&row_w),
            cols,
            mean: mean.map(|m| (m / wsum.max(1e-30)) as f32),
        }
    }

    /// The mean radiance over the sphere (what a white Lambertian surface open to the whole
    /// sky reflects): the Whitted tracer's ambient term.
    pub fn mean(&self) -> V3 {
        self.mean
    }

    /// World direction to the environment's own frame (undoing the rotation about +y).
    #[inline]
    fn to_local(&self, d: V3) -> V3 {
        let (c, s) = self.rot;
        [c * d[0] - s * d[2], d[1], s * d[0] + c * d[2]]
    }

    /// The environment's frame to world: the right-handed rotation about +y
    /// (counter-clockwise seen from above; at 90 degrees -z goes to -x).
    #[inline]
    fn to_world(&self, d: V3) -> V3 {
        let (c, s) = self.rot;
        [c * d[0] + s * d[2], d[1], -s * d[0] + c * d[2]]
    }

    /// The texel (column, row) seen along local unit direction `d`, and sin(theta).
    #[inline]
    fn texel(&self, d: V3) -> (usize, usize, f32) {
        let t = d[1].clamp(-1.0, 1.0).acos();
        let u = 0.5 + d[0].atan2(-d[2]) / (2.0 * PI);
        let v = t / PI;
        let x = ((u * self.w as f32) as usize).min(self.w - 1);
        let y = ((v * self.h as f32) as usize).min(self.h - 1);
        (x, y, t.sin())
    }

    /// Radiance arriving along `-d` from world direction `d` (unit).
    #[inline]
    pub fn eval(&self, d: V3) -> V3 {
        let (x, y, _) = self.texel(self.to_local(d));
        self.px[y * self.w + x]
    }

    /// Solid-angle density with which `sample` returns world direction `d`.
    #[inline]
    pub fn pdf(&self, d: V3) -> f32 {
        if self.rows.is_empty() {
            return 0.0;
        }
        let (x, y, s) = self.texel(self.to_local(d));
        if s <= 0.0 {
            return 0.0;
        }
        let p_uv = self.rows.pmf(y) * self.cols[y].pmf(x) * (self.w * self.h) as f32;
        p_uv / (2.0 * PI * PI * s)
    }

    /// A direction drawn with density proportional to luminance (`None` for a black sky).
    #[inline]
    pub fn sample(&self, u: [f32; 2]) -> Option<EnvSample> {
        if self.rows.is_empty() {
            return None;
        }
        let (y, ry) = self.rows.sample_remapped(u[1]);
        let (x, rx) = self.cols[y].sample_remapped(u[0]);
        let uu = (x as f32 + rx) / self.w as f32;
        let vv = (y as f32 + ry) / self.h as f32;
        let (t, p) = (PI * vv, 2.0 * PI * (uu - 0.5));
        let (st, ct) = t.sin_cos();
        if st <= 0.0 {
            return None;
        }
        let (sp, cp) = p.sin_cos();
        let local = [st * sp, ct, -st * cp];
        let p_uv = self.rows.pmf(y) * self.cols[y].pmf(x) * (self.w * self.h) as f32;
        Some(EnvSample {
            wi: self.to_world(local),
            le: self.px[y * self.w + x],
            pdf: p_uv / (2.0 * PI * PI * st),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::v3::{dot, length};
    use cgnodes_api::rng::Pcg32;

    fn sky() -> Image {
        // A gradient with one bright texel.
        let mut img = Image::new(16, 8, [0.0; 4]);
        for y in 0..8 {
            for x in 0..16 {
                img.set(x, y, [0.1 + 0.05 * x as f32, 0.2, 0.01 * y as f32, 1.0]);
            }
        }
        img.set(11, 2, [50.0, 40.0, 30.0, 1.0]);
        img
    }

    /// Sampled directions have the density `pdf` reports (E[f / pdf] over the sphere is the
    /// integral of f, checked on f = luminance, whose integral is known from uniform
    /// sampling), the direction maps back to the texel it was drawn from, and a rotation
    /// turns the lookup.
    #[test]
    fn sampling_density_matches_pdf_and_lookup() {
        let env = Environment::new(Some(&sky()), [1.0; 3], 30.0);
        let mut r = Pcg32::new(5, 7);
        let n = 200_000;
        let (mut est, mut uni) = (0.0f64, 0.0f64);
        // Directions drawn within rounding of a texel edge may look up the neighbour.
        let mut off = 0;
        for _ in 0..n {
            let s = env.sample(r.next_2d()).unwrap();
            assert!((length(s.wi) - 1.0).abs() < 1e-4);
            if (env.pdf(s.wi) - s.pdf).abs() > 1e-3 * s.pdf || env.eval(s.wi) != s.le {
                off += 1;
            }
            est += (luminance(s.le) / s.pdf) as f64;
            // Uniform sphere sampling of the same integral.
            let u = r.next_2d();
            let z = 1.0 - 2.0 * u[0];
            let rr = (1.0 - z * z).max(0.0).sqrt();
            let d = [
                rr * (2.0 * PI * u[1]).cos(),
                z,
                rr * (2.0 * PI * u[1]).sin(),
            ];
            uni += (luminance(env.eval(d)) * 4.0 * PI) as f64;
        }
        assert!(off <= n / 1000, "{off} samples off their texel");
        let (est, uni) = (est / n as f64, uni / n as f64);
        assert!((est - uni).abs() < 0.02 * uni, "{est} vs {uni}");
        // Rotation by 90 degrees counter-clockwise seen from above: what the unrotated
        // environment shows towards (x, y, z) appears towards (z, y, -x).
        let e0 = Environment::new(Some(&sky()), [1.0; 3], 0.0);
        let e90 = Environment::new(Some(&sky()), [1.0; 3], 90.0);
        for d in [[0.1f32, 0.2, -0.97], [0.7, -0.3, 0.64], [-0.5, 0.6, 0.62]] {
            assert_eq!(e90.eval([d[2], d[1], -d[0]]), e0.eval(d));
        }
        // The bright texel (11, 2) sits where the mapping says: u = 11.5/16, v = 2.5/8.
        let (t, p) = (PI * 2.5 / 8.0, 2.0 * PI * (11.5 / 16.0 - 0.5));
        let d = [t.sin() * p.sin(), t.cos(), -t.sin() * p.cos()];
        assert_eq!(e0.eval(d), [50.0, 40.0, 30.0]);
        assert!((dot(e90.to_world(e90.to_local(d)), d) - 1.0).abs() < 1e-5);
        // The mean of a constant sky is the constant.
        let c = Environment::new(None, [0.5, 1.0, 2.0], 0.0);
        assert!((c.mean()[2] - 2.0).abs() < 1e-5);
    }
}
