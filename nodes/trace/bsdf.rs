//! Scattering models of the tracers, in world space around the geometric normal:
//! two-sided Lambertian diffuse, perfect mirror, smooth dielectric (exact Fresnel, with
//! the 1/eta^2 radiance scaling across refraction, Veach 1997 section 5.2), and a GGX
//! microfacet conductor with Schlick's Fresnel and visible-normal sampling (Heitz 2018,
//! "Sampling the GGX Distribution of Visible Normals", JCGT 7(4)).
//!
//! `weight` of a sample is f cos / pdf, the factor the path throughput is multiplied by.
//!
//! Shading normals (Veach 1997, section 5.3): the lobes are laid out around the shading
//! normal `ns` (interpolated, normal-mapped) while the geometric normal `ng` decides which
//! side of the surface a direction is on. For radiance transport (paths from the camera)
//! Veach's adjoint-consistent BSDF is `f_s(wi, wo) = f(wi, wo) |wi.ns| / |wi.ng|` (eq.
//! 5.19), so the scattering integrand `f_s |wi.ng|` is `f |wi.ns|`: eval returns f cos with
//! the shading cosine, and sampling about `ns` gives weights `f |wi.ns| / pdf`. Against
//! light leaks, a reflected direction must lie on `wo`'s side of the geometric surface and
//! a refracted one on the other side: reflections that the shading normal would send below
//! the surface fall back to the geometric normal (mirror, glass), diffuse and rough samples
//! there are discarded, and eval is zero there. When `wo` itself is below the shading
//! hemisphere (grazing view of a strongly bent normal) the geometric normal is used.

use super::sampling::{add, cosine_hemisphere, dot, normalize, onb, scale, sub, V3};
use std::f32::consts::{FRAC_1_PI, PI};

/// A scattering model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    /// Lambertian, f = albedo / pi, reflecting on both faces.
    Diffuse,
    /// Perfect specular reflection tinted by the albedo.
    Mirror,
    /// Smooth glass with relative index of refraction `eta` (inside over outside).
    Dielectric { eta: f32 },
    /// Rough metal, GGX with width `alpha`; F0 is the albedo.
    Conductor { alpha: f32 },
}

/// A sampled direction.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Unit direction the path continues in.
    pub wi: V3,
    /// f cos / pdf.
    pub weight: V3,
    /// Solid-angle density (1 for delta lobes, whose pdf is not a density).
    pub pdf: f32,
    /// Whether the lobe is a Dirac delta (mirror, glass).
    pub delta: bool,
    /// Relative index of refraction crossed (1 unless refracted), for Russian roulette.
    pub eta: f32,
}

/// Mirror reflection of `wo` about `n`.
#[inline(always)]
pub fn reflect(wo: V3, n: V3) -> V3 {
    sub(scale(n, 2.0 * dot(wo, n)), wo)
}

/// Unpolarised Fresnel reflectance of a smooth dielectric interface (Walter et al. 2007,
/// eq. 22 form). `cos_i` is measured on the incident side, `eta` = n_t / n_i. Returns
/// (F, cos_t).
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> (f32, f32) {
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    (0.5 * (rs * rs + rp * rp), cos_t)
}

/// Schlick's approximation of conductor Fresnel with normal-incidence reflectance `f0`.
#[inline]
fn schlick(f0: V3, cos: f32) -> V3 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m5 = m * m * m * m * m;
    [
        f0[0] + (1.0 - f0[0]) * m5,
        f0[1] + (1.0 - f0[1]) * m5,
        f0[2] + (1.0 - f0[2]) * m5,
    ]
}

/// GGX normal distribution D(h) in the local frame (Walter et al. 2007, eq. 33).
#[inline]
fn ggx_d(h: V3, a: f32) -> f32 {
    let t = h[0] * h[0] / (a * a) + h[1] * h[1] / (a * a) + h[2] * h[2];
    1.0 / (PI * a * a * t * t)
}

/// Smith Lambda for GGX (Heitz 2014, eq. 72).
#[inline]
fn ggx_lambda(w: V3, a: f32) -> f32 {
    let c2 = w[2] * w[2];
    let s2 = (1.0 - c2).max(0.0);
    if c2 <= 0.0 {
        return f32::INFINITY;
    }
    0.5 * ((1.0 + a * a * s2 / c2).sqrt() - 1.0)
}

fn to_local(v: V3, t: V3, b: V3, n: V3) -> V3 {
    [dot(v, t), dot(v, b), dot(v, n)]
}

fn to_world(v: V3, t: V3, b: V3, n: V3) -> V3 {
    add(add(scale(t, v[0]), scale(b, v[1])), scale(n, v[2]))
}

/// Samples a GGX visible normal for local `wo` (Heitz 2018, Listing 1).
fn sample_vndf(wo: V3, a: f32, u: [f32; 2]) -> V3 {
    let vh = normalize([a * wo[0], a * wo[1], wo[2]]);
    let lensq = vh[0] * vh[0] + vh[1] * vh[1];
    let t1 = if lensq > 0.0 {
        scale([-vh[1], vh[0], 0.0], 1.0 / lensq.sqrt())
    } else {
        [1.0, 0.0, 0.0]
    };
    let t2 = [
        vh[1] * t1[2] - vh[2] * t1[1],
        vh[2] * t1[0] - vh[0] * t1[2],
        vh[0] * t1[1] - vh[1] * t1[0],
    ];
    let r = u[0].sqrt();
    let phi = 2.0 * PI * u[1];
    let p1 = r * phi.cos();
    let mut p2 = r * phi.sin();
    let s = 0.5 * (1.0 + vh[2]);
    p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
    let nh = add(
        add(scale(t1, p1), scale(t2, p2)),
        scale(vh, (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt()),
    );
    normalize([a * nh[0], a * nh[1], nh[2].max(1e-6)])
}

impl Bsdf {
    /// Whether every lobe is a Dirac delta (next-event estimation is pointless there).
    #[inline]
    pub fn is_delta(&self) -> bool {
        matches!(self, Bsdf::Mirror | Bsdf::Dielectric { .. })
    }

    /// f cos for directions `wo` (toward the viewer) and `wi` (toward the light) at a
    /// surface with unit geometric normal `ng` and unit shading normal `ns` (on `ng`'s
    /// side); zero for delta lobes.
    #[inline]
    pub fn eval(&self, albedo: V3, ng: V3, ns: V3, wo: V3, wi: V3) -> V3 {
        self.eval_pdf(albedo, ng, ns, wo, wi).0
    }

    /// Solid-angle density with which `sample` returns `wi`; zero for delta lobes.
    #[inline]
    pub fn pdf(&self, ng: V3, ns: V3, wo: V3, wi: V3) -> f32 {
        self.eval_pdf([0.0; 3], ng, ns, wo, wi).1
    }

    /// `eval` and `pdf` together (as Mitsuba 3's `eval_pdf`): next-event estimation with
    /// MIS needs both for the same pair of directions, and they share the side tests and,
    /// for GGX, the local frame, the half vector and the masking terms.
    ///
    /// Inlined (the diffuse case is a few multiplies; a call returned its pair through
    /// memory, read back before the stores had landed), the GGX case out of line.
    #[inline(always)]
    pub fn eval_pdf(&self, albedo: V3, ng: V3, ns: V3, wo: V3, wi: V3) -> (V3, f32) {
        let Some((g, n)) = sides(ng, ns, wo) else {
            return ([0.0; 3], 0.0);
        };
        let ci = dot(n, wi);
        if ci <= 0.0 || dot(g, wi) <= 0.0 {
            return ([0.0; 3], 0.0);
        }
        match *self {
            Bsdf::Diffuse => (scale(albedo, ci * FRAC_1_PI), ci * FRAC_1_PI),
            Bsdf::Conductor { alpha } => ggx_eval_pdf(albedo, alpha, n, wo, wi),
            _ => ([0.0; 3], 0.0),
        }
    }

    /// Samples a direction given `wo` (unit, toward the viewer), the unit geometric and
    /// shading normals `ng` and `ns`, and three uniform numbers.
    #[inline]
    pub fn sample(
        &self,
        albedo: V3,
        ng: V3,
        ns: V3,
        wo: V3,
        u: f32,
        uv: [f32; 2],
    ) -> Option<BsdfSample> {
        let (g, n) = sides(ng, ns, wo)?;
        match *self {
            Bsdf::Diffuse => {
                let wi = cosine_hemisphere(n, uv);
                let ci = dot(n, wi);
                if ci <= 0.0 || dot(g, wi) <= 0.0 {
                    return None;
                }
                Some(BsdfSample {
                    wi,
                    weight: albedo,
                    pdf: ci * FRAC_1_PI,
                    delta: false,
                    eta: 1.0,
                })
            }
            Bsdf::Mirror => {
                let mut wi = reflect(wo, n);
                if dot(g, wi) <= 0.0 {
                    wi = reflect(wo, g);
                }
                Some(BsdfSample {
                    wi,
                    weight: albedo,
                    pdf: 1.0,
                    delta: true,
                    eta: 1.0,
                })
            }
            Bsdf::Dielectric { eta } => {
                let eta_rel = if dot(ng, wo) > 0.0 { eta } else { 1.0 / eta };
                let s = sample_dielectric(wo, n, eta_rel, u);
                // Reflection must stay on wo's side of the surface, refraction cross it.
                if (dot(g, s.wi) > 0.0) == (s.eta == 1.0) {
                    Some(s)
                } else {
                    Some(sample_dielectric(wo, g, eta_rel, u))
                }
            }
            Bsdf::Conductor { alpha } => {
                let (t, b) = onb(n);
                let lo = to_local(wo, t, b, n);
                let h = sample_vndf(lo, alpha, uv);
                let li = sub(scale(h, 2.0 * dot(lo, h)), lo);
                let wi = to_world(li, t, b, n);
                if li[2] <= 0.0 || dot(g, wi) <= 0.0 {
                    return None;
                }
                let g1o = 1.0 / (1.0 + ggx_lambda(lo, alpha));
                let g2 = 1.0 / (1.0 + ggx_lambda(lo, alpha) + ggx_lambda(li, alpha));
                let f = schlick(albedo, dot(li, h));
                Some(BsdfSample {
                    wi,
                    weight: scale(f, g2 / g1o),
                    pdf: g1o * ggx_d(h, alpha) / (4.0 * lo[2]),
                    delta: false,
                    eta: 1.0,
                })
            }
        }
    }
}

/// The geometric normal flipped to `wo`'s side and the shading normal with it; the shading
/// normal is replaced by the geometric one when `wo` is below its hemisphere. `None` when
/// `wo` grazes the surface.
#[inline]
fn sides(ng: V3, ns: V3, wo: V3) -> Option<(V3, V3)> {
    let co = dot(ng, wo);
    if co == 0.0 || !co.is_finite() {
        return None;
    }
    let s = if co < 0.0 { -1.0 } else { 1.0 };
    let g = scale(ng, s);
    let n = scale(ns, s);
    Some(if dot(n, wo) <= 1e-4 { (g, g) } else { (g, n) })
}

/// The GGX conductor's f cos and visible-normal density for `wo`, `wi` on the side of the
/// unit shading normal `n` (Heitz 2018, eq. 17 over the reflection Jacobian 1 / (4 wo.h)).
#[inline(never)]
fn ggx_eval_pdf(albedo: V3, alpha: f32, n: V3, wo: V3, wi: V3) -> (V3, f32) {
    let (t, b) = onb(n);
    let lo = to_local(wo, t, b, n);
    let li = to_local(wi, t, b, n);
    let h = normalize(add(lo, li));
    let (lam_o, lam_i) = (ggx_lambda(lo, alpha), ggx_lambda(li, alpha));
    let d = ggx_d(h, alpha);
    let g2 = 1.0 / (1.0 + lam_o + lam_i);
    let f = schlick(albedo, dot(li, h));
    // Visible-normal density over the reflection Jacobian 1 / (4 wo.h).
    let g1 = 1.0 / (1.0 + lam_o);
    let q = d / (4.0 * lo[2]);
    (scale(f, g2 * q), g1 * q)
}

/// Smooth dielectric sampling about unit normal `n` on `wo`'s side, relative index
/// `eta_rel` (transmitted over incident): Fresnel-weighted choice between reflection and
/// refraction, the refracted radiance scaled by 1/eta^2.
#[inline]
fn sample_dielectric(wo: V3, n: V3, eta_rel: f32, u: f32) -> BsdfSample {
    let cos_i = dot(n, wo).abs();
    let (f, cos_t) = fresnel_dielectric(cos_i, eta_rel);
    if u < f {
        BsdfSample {
            wi: reflect(wo, n),
            weight: [1.0; 3],
            pdf: f,
            delta: true,
            eta: 1.0,
        }
    } else {
        // Snell: wi = -wo / eta + (cos_i / eta - cos_t) n.
        let wi = normalize(add(
            scale(wo, -1.0 / eta_rel),
            scale(n, cos_i / eta_rel - cos_t),
        ));
        let s = 1.0 / (eta_rel * eta_rel);
        BsdfSample {
            wi,
            weight: [s; 3],
            pdf: 1.0 - f,
            delta: true,
            eta: eta_rel,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{length, Pcg32};

    #[test]
    fn fresnel_matches_known_values() {
        // Normal incidence: ((eta-1)/(eta+1))^2 = 0.04 for eta 1.5.
        assert!((fresnel_dielectric(1.0, 1.5).0 - 0.04).abs() < 1e-6);
        // Total internal reflection beyond the critical angle from glass.
        assert_eq!(fresnel_dielectric(0.3, 1.0 / 1.5).0, 1.0);
        // Brewster angle: rp = 0, so F = rs^2 / 2.
        let tb = 1.5f32.atan();
        let (f, ct) = fresnel_dielectric(tb.cos(), 1.5);
        let rs = (tb.cos() - 1.5 * ct) / (tb.cos() + 1.5 * ct);
        assert!((f - 0.5 * rs * rs).abs() < 1e-6);
    }

    #[test]
    fn conductor_sampling_matches_eval_over_pdf() {
        // weight = f cos / pdf for sampled directions, and the pdf integrates to <= 1
        // (estimated by uniform hemisphere sampling).
        let ng = [0.0, 0.0, 1.0];
        let wo = normalize([0.4, 0.1, 0.8]);
        let m = Bsdf::Conductor { alpha: 0.3 };
        let alb = [0.9, 0.6, 0.3];
        let mut r = Pcg32::new(1, 1);
        for _ in 0..1000 {
            if let Some(s) = m.sample(alb, ng, ng, wo, r.next_f32(), r.next_2d()) {
                assert!((length(s.wi) - 1.0).abs() < 1e-4);
                let f = m.eval(alb, ng, ng, wo, s.wi);
                let p = m.pdf(ng, ng, wo, s.wi);
                for (k, fk) in f.iter().enumerate() {
                    assert!((fk / p - s.weight[k]).abs() < 1e-3 * (1.0 + s.weight[k]));
                }
            }
        }
        let k = 200_000;
        let mut integral = 0.0f64;
        for _ in 0..k {
            let u = r.next_2d();
            let z = u[0];
            let s = (1.0 - z * z).sqrt();
            let wi = [s * (2.0 * PI * u[1]).cos(), s * (2.0 * PI * u[1]).sin(), z];
            integral += (m.pdf(ng, ng, wo, wi) * 2.0 * PI) as f64;
        }
        let integral = integral / k as f64;
        assert!(
            integral < 1.01 && integral > 0.9,
            "pdf integrates to {integral}"
        );
    }

    #[test]
    fn dielectric_refraction_obeys_snell() {
        let ng = [0.0, 0.0, 1.0];
        let wo = normalize([0.5, 0.0, 1.0]);
        let m = Bsdf::Dielectric { eta: 1.5 };
        let s = m.sample([1.0; 3], ng, ng, wo, 0.99, [0.0, 0.0]).unwrap();
        let sin_i = (1.0 - wo[2] * wo[2]).sqrt();
        let sin_t = (1.0 - s.wi[2] * s.wi[2]).sqrt();
        assert!(s.wi[2] < 0.0);
        assert!((sin_i - 1.5 * sin_t).abs() < 1e-5);
        assert!((s.weight[0] - 1.0 / 2.25).abs() < 1e-6);
    }
}
