//! Sampling, cropping and pasting on `Image`, shared by every image node.
//!
//! Coordinates are continuous pixel units: the origin is the top-left corner of the top-left
//! pixel, x grows to the right and y down, so the centre of pixel (i, j) is (i + 0.5, j + 0.5).
//! A point outside the image (x outside [0, width] or y outside [0, height]) samples as
//! transparent black [0, 0, 0, 0].

use super::Image;

/// Transparent black: what a sample outside the image returns.
pub const TRANSPARENT: [f32; 4] = [0.0; 4];

/// Fractions within this distance of 0 or 1 (in pixels) are snapped to the pixel centre, so a
/// map that reproduces the pixel centres up to rounding (an identity warp) copies pixels
/// exactly instead of mixing in 1e-16 of a neighbour.
const SNAP: f64 = 1e-9;

impl Image {
    /// Whether (x, y) lies inside the image's rectangle [0, width] x [0, height].
    pub fn contains(&self, x: f64, y: f64) -> bool {
        x >= 0.0 && y >= 0.0 && x <= self.width as f64 && y <= self.height as f64
    }

    /// The pixel covering (x, y) (nearest-neighbour sampling): pixel (floor x, floor y), the
    /// right and bottom edges belonging to the last column and row. Outside: transparent black.
    pub fn sample_nearest(&self, x: f64, y: f64) -> [f32; 4] {
        if !self.contains(x, y) || self.pixels.is_empty() {
            return TRANSPARENT;
        }
        let i = (x.floor() as u32).min(self.width - 1);
        let j = (y.floor() as u32).min(self.height - 1);
        self.get(i, j)
    }

    /// Bilinear interpolation of the four pixel centres around (x, y). Inside the half-pixel
    /// border band the nearest centres are repeated (clamp to edge); outside the image the
    /// sample is transparent black. At a pixel centre the pixel comes back exactly.
    pub fn sample_bilinear(&self, x: f64, y: f64) -> [f32; 4] {
        if !self.contains(x, y) || self.pixels.is_empty() {
            return TRANSPARENT;
        }
        let (i0, i1, tx) = axis(x, self.width);
        let (j0, j1, ty) = axis(y, self.height);
        let w = self.width as usize;
        let p = |i: usize, j: usize| self.pixels[j * w + i];
        if tx == 0.0 && ty == 0.0 {
            return p(i0, j0);
        }
        let (a, b, c, d) = (p(i0, j0), p(i1, j0), p(i0, j1), p(i1, j1));
        let (tx, ty) = (tx as f32, ty as f32);
        let mut out = [0.0f32; 4];
        for k in 0..4 {
            let top = a[k] + (b[k] - a[k]) * tx;
            let bottom = c[k] + (d[k] - c[k]) * tx;
            out[k] = top + (bottom - top) * ty;
        }
        out
    }

    /// The `w` x `h` rectangle whose top-left pixel is (x, y) of this image; pixels of the
    /// rectangle outside this image are transparent black.
    pub fn crop(&self, x: i64, y: i64, w: u32, h: u32) -> Image {
        let mut out = Image::new(w, h, TRANSPARENT);
        out.paste(self, -x, -y);
        out
    }

    /// Copies `other` onto this image with its top-left pixel at (x, y), replacing the pixels
    /// it covers (no blending); the part of `other` outside this image is dropped.
    pub fn paste(&mut self, other: &Image, x: i64, y: i64) {
        let (sw, sh) = (self.width as i64, self.height as i64);
        let (ow, oh) = (other.width as i64, other.height as i64);
        let x0 = x.max(0);
        let x1 = (x + ow).min(sw);
        if x1 <= x0 {
            return;
        }
        for j in y.max(0)..(y + oh).min(sh) {
            let dst = (j * sw + x0) as usize;
            let src = ((j - y) * ow + (x0 - x)) as usize;
            let n = (x1 - x0) as usize;
            self.pixels[dst..dst + n].copy_from_slice(&other.pixels[src..src + n]);
        }
    }
}

/// The two pixel indices around coordinate `x` along an axis of `n` pixels and the fraction
/// of the second (clamped to edge, snapped to 0 near a centre).
fn axis(x: f64, n: u32) -> (usize, usize, f64) {
    let u = x - 0.5;
    let f = u.floor();
    let mut t = u - f;
    let mut i0 = f as i64;
    if t < SNAP {
        t = 0.0;
    } else if t > 1.0 - SNAP {
        t = 0.0;
        i0 += 1;
    }
    let last = n as i64 - 1;
    let i1 = (i0 + 1).clamp(0, last) as usize;
    (i0.clamp(0, last) as usize, i1, t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3x2 image whose pixel (i, j) has red = i, green = j.
    fn ramp() -> Image {
        let mut im = Image::new(3, 2, [0.0; 4]);
        for j in 0..2 {
            for i in 0..3 {
                im.set(i, j, [i as f32, j as f32, 0.5, 1.0]);
            }
        }
        im
    }

    #[test]
    fn nearest_picks_the_covering_pixel_and_outside_is_transparent() {
        let im = ramp();
        assert_eq!(im.sample_nearest(2.9, 1.2), [2.0, 1.0, 0.5, 1.0]);
        assert_eq!(im.sample_nearest(0.0, 0.0), [0.0, 0.0, 0.5, 1.0]);
        assert_eq!(im.sample_nearest(3.0, 2.0), [2.0, 1.0, 0.5, 1.0]);
        assert_eq!(im.sample_nearest(-0.01, 1.0), TRANSPARENT);
        assert_eq!(im.sample_nearest(1.0, 2.01), TRANSPARENT);
        assert_eq!(im.sample_nearest(f64::NAN, 1.0), TRANSPARENT);
    }

    #[test]
    fn bilinear_is_exact_at_centres_and_linear_between() {
        let im = ramp();
        for j in 0..2 {
            for i in 0..3 {
                let s = im.sample_bilinear(i as f64 + 0.5, j as f64 + 0.5);
                assert_eq!(s, im.get(i, j));
            }
        }
        // Red is i = x - 0.5 and green j = y - 0.5 between the centres: linear in both.
        let s = im.sample_bilinear(1.25, 1.1);
        assert!((s[0] - 0.75).abs() < 1e-6 && (s[1] - 0.6).abs() < 1e-6);
        // Border band: clamped to the edge pixels.
        assert_eq!(im.sample_bilinear(0.1, 0.2)[0], 0.0);
        assert_eq!(im.sample_bilinear(2.9, 1.9), im.get(2, 1));
        // Within 1e-9 px of a centre the pixel comes back exactly.
        assert_eq!(im.sample_bilinear(1.5 + 1e-12, 0.5 - 1e-12), im.get(1, 0));
        assert_eq!(im.sample_bilinear(3.5, 1.0), TRANSPARENT);
        assert_eq!(im.sample_bilinear(1.0, -0.5), TRANSPARENT);
    }

    #[test]
    fn crop_and_paste_round_trip_and_clip() {
        let im = ramp();
        let c = im.crop(1, 0, 2, 2);
        assert_eq!((c.width, c.height), (2, 2));
        assert_eq!(c.get(0, 0), im.get(1, 0));
        assert_eq!(c.get(1, 1), im.get(2, 1));
        // Partly outside: the rest is transparent.
        let c = im.crop(-1, 1, 2, 2);
        assert_eq!(c.get(0, 0), TRANSPARENT);
        assert_eq!(c.get(1, 0), im.get(0, 1));
        assert_eq!(c.get(1, 1), TRANSPARENT);
        // Paste clips on every side.
        let mut big = Image::new(4, 4, [9.0; 4]);
        big.paste(&im, 2, -1);
        assert_eq!(big.get(2, 0), im.get(0, 1));
        assert_eq!(big.get(3, 0), im.get(1, 1));
        assert_eq!(big.get(1, 0), [9.0; 4]);
        assert_eq!(big.get(2, 1), [9.0; 4]);
        big.paste(&im, 10, 10);
        big.paste(&im, -5, 0);
        assert_eq!(big.get(0, 0), [9.0; 4]);
        let mut back = Image::new(3, 2, TRANSPARENT);
        back.paste(&im.crop(0, 0, 3, 2), 0, 0);
        assert_eq!(back, im);
    }
}
