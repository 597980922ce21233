//! Small operations on the tracers' f32 3-vectors (`V3`), their working precision (the f64
//! counterparts for mesh positions are in `cgnodes_api::types::vec3`).

/// A 3-vector of f32, the renderer's working precision.
pub type V3 = [f32; 3];

/// `a + b`.
#[inline(always)]
pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
/// `a - b`.
#[inline(always)]
pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
/// `a * s`.
#[inline(always)]
pub fn scale(a: V3, s: f32) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
/// Component-wise product.
#[inline(always)]
pub fn mul(a: V3, b: V3) -> V3 {
    [a[0] * b[0], a[1] * b[1], a[2] * b[2]]
}
/// Dot product.
#[inline(always)]
pub fn dot(a: V3, b: V3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
/// Cross product.
#[inline(always)]
pub fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
/// Euclidean length.
#[inline(always)]
pub fn length(a: V3) -> f32 {
    dot(a, a).sqrt()
}
/// `a / |a|` (returns `a` unchanged when it has zero length).
#[inline(always)]
pub fn normalize(a: V3) -> V3 {
    let l = length(a);
    if l > 0.0 {
        scale(a, 1.0 / l)
    } else {
        a
    }
}
/// The largest component.
#[inline(always)]
pub fn max_comp(a: V3) -> f32 {
    a[0].max(a[1]).max(a[2])
}
/// Converts an f64 triple to the renderer's f32.
#[inline(always)]
pub fn v3(a: [f64; 3]) -> V3 {
    [a[0] as f32, a[1] as f32, a[2] as f32]
}
/// Rec. 709 luminance of a linear RGB triple.
#[inline(always)]
pub fn luminance(c: V3) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}
