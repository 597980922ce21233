//! Gradient energy e1 (Avidan & Shamir 2007, eq. 1): |∂I/∂x| + |∂I/∂y| of the luminance,
//! with Sobel derivatives and the border pixels repeated (what scipy's `sobel` with mode
//! `reflect` computes, as the `seam-carving` peer does).

/// Rec. 709 luminance of linear RGB; a grey pixel's own value exactly (the weights sum to
/// one, but their rounding would make equal greys differ in the last bit).
pub fn luminance(p: [f32; 4]) -> f64 {
    if p[0] == p[1] && p[1] == p[2] {
        return p[0] as f64;
    }
    0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
}

/// e1 at (x, y) of the `w x h` gray image `g`.
#[inline]
pub fn backward_at(g: &[f64], w: usize, h: usize, x: usize, y: usize) -> f64 {
    let xm = x.saturating_sub(1);
    let xp = (x + 1).min(w - 1);
    let ym = y.saturating_sub(1);
    let yp = (y + 1).min(h - 1);
    let at = |xx: usize, yy: usize| g[yy * w + xx];
    // Sobel: derivative [-1, 0, 1] across, smoothing [1, 2, 1] along
    let gx = (at(xp, ym) - at(xm, ym)) + 2.0 * (at(xp, y) - at(xm, y)) + (at(xp, yp) - at(xm, yp));
    let gy = (at(xm, yp) - at(xm, ym)) + 2.0 * (at(x, yp) - at(x, ym)) + (at(xp, yp) - at(xp, ym));
    gx.abs() + gy.abs()
}

/// e1 of every pixel.
pub fn backward_map(g: &[f64], w: usize, h: usize) -> Vec<f64> {
    let mut e = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            e.push(backward_at(g, w, h, x, y));
        }
    }
    e
}
