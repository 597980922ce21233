//! The sRGB transfer functions (IEC 61966-2-1): 8- and 16-bit colour files store sRGB-encoded
//! values, the renderers work in linear RGB.

/// The sRGB electro-optical transfer function: encoded value in 0..1 to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The inverse sRGB transfer function: linear (clamped to 0..1) to encoded.
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_curve_round_trips_and_hits_known_values() {
        // sRGB 0.5 is linear 0.2140 (IEC 61966-2-1).
        assert!((srgb_to_linear(0.5) - 0.21404).abs() < 1e-4);
        assert_eq!(linear_to_srgb(0.0), 0.0);
        assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
        for i in 0..=255 {
            let v = i as f32 / 255.0;
            assert!((linear_to_srgb(srgb_to_linear(v)) - v).abs() < 1e-5);
        }
    }
}
