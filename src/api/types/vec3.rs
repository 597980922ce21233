//! Small operations on `[f64; 3]` points and vectors, the form meshes store positions in,
//! shared by the geometry, rendering and simulation nodes.

/// `a - b`.
#[inline]
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a + b`.
#[inline]
pub fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `a + s b`.
#[inline]
pub fn axpy(a: [f64; 3], s: f64, b: [f64; 3]) -> [f64; 3] {
    [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]]
}

/// `s a`.
#[inline]
pub fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// Dot product.
#[inline]
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Cross product `a x b`.
#[inline]
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Euclidean norm.
#[inline]
pub fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// `a - b` in the plane.
#[inline]
pub fn sub2(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

/// The 2-D cross product `a.x b.y - a.y b.x` (twice the signed area of the triangle `0, a, b`).
#[inline]
pub fn cross2(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// `a / |a|`, or `None` when `|a|` is not a finite number above 1e-300 (a zero, tiny,
/// infinite or NaN vector).
#[inline]
pub fn normalize(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = dot(a, a).sqrt();
    (n > 1e-300 && n.is_finite()).then(|| [a[0] / n, a[1] / n, a[2] / n])
}

/// `normalize` computed as one division and three products (`a * (1 / |a|)`): cheaper where
/// many vectors are normalized per sample, and rounded differently from `normalize` in the
/// last bit, so each caller keeps the form it was tuned with.
#[inline]
pub fn normalize_recip(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = dot(a, a).sqrt();
    (n > 1e-300 && n.is_finite()).then(|| {
        let r = 1.0 / n;
        [a[0] * r, a[1] * r, a[2] * r]
    })
}

/// `a / |a|` without a check: callers that know `a` is not zero (a zero vector gives NaN).
#[inline]
pub fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    [a[0] / n, a[1] / n, a[2] / n]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cross_is_orthogonal_and_right_handed() {
        let (a, b) = ([1.0, 2.0, 3.0], [-2.0, 0.5, 4.0]);
        let c = cross(a, b);
        assert!(dot(c, a).abs() < 1e-12 && dot(c, b).abs() < 1e-12);
        assert_eq!(cross([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]);
        assert_eq!(norm([3.0, 4.0, 0.0]), 5.0);
        assert_eq!(axpy(a, 2.0, b), add(a, scale(b, 2.0)));
        assert_eq!(sub(add(a, b), b), a);
        assert_eq!(normalize([0.0, 3.0, 4.0]), Some([0.0, 0.6, 0.8]));
        assert_eq!(normalize([0.0; 3]), None);
        assert_eq!(normalize_recip([f64::NAN, 0.0, 0.0]), None);
        assert_eq!(unit([2.0, 0.0, 0.0]), [1.0, 0.0, 0.0]);
    }
}
