//! Texture sampling: bilinear filtering with wrap modes, and a mipmap pyramid with
//! trilinear filtering (Williams, "Pyramidal Parametrics", SIGGRAPH 1983) so that a
//! far-away checkerboard averages to grey instead of aliasing into moire.
//!
//! UV (0, 0) is the image's bottom-left corner and v grows upwards (the OpenGL and USD
//! convention); texel centres sit at `(i + 0.5) / width`.

use cgnodes_api::prelude::*;

/// What happens to UVs outside 0..1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    /// The texture tiles.
    Repeat,
    /// Edge texels extend.
    Clamp,
    /// The texture tiles, mirrored every other time.
    Mirror,
}

impl Wrap {
    /// Maps a texel index into `0..n`.
    #[inline]
    fn index(self, i: i64, n: usize) -> usize {
        let n = n as i64;
        (match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::Clamp => i.clamp(0, n - 1),
            Wrap::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m < n {
                    m
                } else {
                    2 * n - 1 - m
                }
            }
        }) as usize
    }
}

/// One level of a mipmap pyramid.
#[derive(Clone, Debug)]
struct Level {
    w: usize,
    h: usize,
    px: Vec<[f32; 4]>,
}

/// A texture with its mipmap pyramid (level 0 is the image).
#[derive(Clone, Debug)]
pub struct MipTexture {
    levels: Vec<Level>,
}

impl MipTexture {
    /// Builds the pyramid by 2x2 box filtering down to 1x1 (only level 0 when
    /// `mipmaps` is false). Odd sizes round down; the last row or column folds in.
    pub fn new(img: &Image, mipmaps: bool) -> MipTexture {
        let (w, h) = (img.width as usize, img.height as usize);
        let level0 = if w > 0 && h > 0 && img.pixels.len() == w * h {
            Level {
                w,
                h,
                px: img.pixels.clone(),
            }
        } else {
            // A malformed image samples as white rather than reading out of bounds.
            Level {
                w: 1,
                h: 1,
                px: vec![[1.0; 4]],
            }
        };
        let mut levels = vec![level0];
        loop {
            let l = levels.last().expect("level 0 exists");
            if !mipmaps || (l.w == 1 && l.h == 1) {
                break;
            }
            let (w, h) = ((l.w / 2).max(1), (l.h / 2).max(1));
            let mut px = vec![[0.0f32; 4]; w * h];
            for y in 0..h {
                // Source rows covered by this texel (3 at the end of an odd size).
                let ys: Vec<usize> = (2 * y..(2 * y + 2).min(l.h))
                    .chain((y == h - 1 && l.h > 2 * h).then_some(l.h - 1))
                    .collect();
                for x in 0..w {
                    let xs: Vec<usize> = (2 * x..(2 * x + 2).min(l.w))
                        .chain((x == w - 1 && l.w > 2 * w).then_some(l.w - 1))
                        .collect();
                    let mut acc = [0.0f32; 4];
                    for &sy in &ys {
                        for &sx in &xs {
                            let p = l.px[sy * l.w + sx];
                            for k in 0..4 {
                                acc[k] += p[k];
                            }
                        }
                    }
                    let n = (ys.len() * xs.len()) as f32;
                    px[y * w + x] = acc.map(|a| a / n);
                }
            }
            levels.push(Level { w, h, px });
        }
        MipTexture { levels }
    }

    /// Number of pyramid levels.
    pub fn num_levels(&self) -> usize {
        self.levels.len()
    }

    /// Size of level 0.
    pub fn size(&self) -> (usize, usize) {
        (self.levels[0].w, self.levels[0].h)
    }

    /// Bilinear sample of one level.
    pub fn bilinear(&self, level: usize, u: f64, v: f64, wrap: Wrap) -> [f32; 4] {
        let l = &self.levels[level.min(self.levels.len() - 1)];
        let x = u * l.w as f64 - 0.5;
        let y = (1.0 - v) * l.h as f64 - 0.5;
        if !(x.is_finite() && y.is_finite()) {
            return l.px[0];
        }
        let (xf, yf) = (x.floor(), y.floor());
        let (fx, fy) = ((x - xf) as f32, (y - yf) as f32);
        let (x0, y0) = (xf as i64, yf as i64);
        let xa = wrap.index(x0, l.w);
        let xb = wrap.index(x0 + 1, l.w);
        let ya = wrap.index(y0, l.h);
        let yb = wrap.index(y0 + 1, l.h);
        let p = |x: usize, y: usize| l.px[y * l.w + x];
        let (p00, p10, p01, p11) = (p(xa, ya), p(xb, ya), p(xa, yb), p(xb, yb));
        std::array::from_fn(|k| {
            let top = p00[k] + (p10[k] - p00[k]) * fx;
            let bot = p01[k] + (p11[k] - p01[k]) * fx;
            top + (bot - top) * fy
        })
    }

    /// Trilinear sample: the level of detail is `log2` of the larger screen-space
    /// footprint of one pixel in texels, `max(|d(uv)/dx|, |d(uv)/dy|)` scaled by the size;
    /// the two nearest levels are blended.
    pub fn trilinear(
        &self,
        u: f64,
        v: f64,
        duv_dx: [f64; 2],
        duv_dy: [f64; 2],
        wrap: Wrap,
    ) -> [f32; 4] {
        let (w, h) = (self.levels[0].w as f64, self.levels[0].h as f64);
        let lx = (duv_dx[0] * w).hypot(duv_dx[1] * h);
        let ly = (duv_dy[0] * w).hypot(duv_dy[1] * h);
        let rho = lx.max(ly);
        let lod = if rho > 1.0 && rho.is_finite() {
            rho.log2().min((self.levels.len() - 1) as f64)
        } else {
            0.0
        };
        let l0 = lod.floor() as usize;
        let t = (lod - l0 as f64) as f32;
        let a = self.bilinear(l0, u, v, wrap);
        if t <= 0.0 || l0 + 1 >= self.levels.len() {
            return a;
        }
        let b = self.bilinear(l0 + 1, u, v, wrap);
        std::array::from_fn(|k| a[k] + (b[k] - a[k]) * t)
    }
}

impl cgnodes_api::node::Choice for Wrap {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("repeat", Wrap::Repeat),
        ("clamp", Wrap::Clamp),
        ("mirror", Wrap::Mirror),
    ];
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker(n: u32) -> Image {
        let mut img = Image::new(n, n, [0.0, 0.0, 0.0, 1.0]);
        for y in 0..n {
            for x in 0..n {
                if (x + y) % 2 == 0 {
                    img.set(x, y, [1.0, 1.0, 1.0, 1.0]);
                }
            }
        }
        img
    }

    #[test]
    fn bilinear_hits_texel_centres_and_midpoints() {
        let mut img = Image::new(2, 1, [0.0; 4]);
        img.set(1, 0, [1.0; 4]);
        let t = MipTexture::new(&img, false);
        // Texel centres at u = 0.25, 0.75.
        assert_eq!(t.bilinear(0, 0.25, 0.5, Wrap::Clamp)[0], 0.0);
        assert_eq!(t.bilinear(0, 0.75, 0.5, Wrap::Clamp)[0], 1.0);
        assert!((t.bilinear(0, 0.5, 0.5, Wrap::Clamp)[0] - 0.5).abs() < 1e-6);
        // Repeat: at u = 0 the texel to the left is texel 1, so halfway gives 0.5.
        assert!((t.bilinear(0, 0.0, 0.5, Wrap::Repeat)[0] - 0.5).abs() < 1e-6);
        assert_eq!(t.bilinear(0, 0.0, 0.5, Wrap::Clamp)[0], 0.0);
        // Repeat is periodic; mirror reflects at 1.
        let a = t.bilinear(0, 0.3, 0.5, Wrap::Repeat)[0];
        assert!((t.bilinear(0, 2.3, 0.5, Wrap::Repeat)[0] - a).abs() < 1e-6);
        let m = t.bilinear(0, 1.2, 0.5, Wrap::Mirror)[0];
        assert!((m - t.bilinear(0, 0.8, 0.5, Wrap::Mirror)[0]).abs() < 1e-6);
    }

    #[test]
    fn pyramid_keeps_the_mean_and_minified_checker_is_grey() {
        let img = checker(64);
        let t = MipTexture::new(&img, true);
        assert_eq!(t.num_levels(), 7);
        // Every level of a checkerboard above 1x1 texel squares averages to 0.5; the
        // first downsampled level is already uniform grey.
        let g = t.bilinear(1, 0.37, 0.61, Wrap::Repeat)[0];
        assert!((g - 0.5).abs() < 1e-6);
        // A footprint of 4 texels per pixel samples level 2: grey, whatever the position.
        for i in 0..20 {
            let u = i as f64 * 0.0731;
            let c = t.trilinear(u, 0.3, [4.0 / 64.0, 0.0], [0.0, 4.0 / 64.0], Wrap::Repeat);
            assert!((c[0] - 0.5).abs() < 1e-5);
        }
        // Magnified: level 0.
        let c = t.trilinear(
            0.5 / 64.0,
            1.0 - 0.5 / 64.0,
            [1e-4, 0.0],
            [0.0, 1e-4],
            Wrap::Repeat,
        );
        assert_eq!(c[0], 1.0);
    }

    #[test]
    fn odd_sizes_average_every_texel() {
        let mut img = Image::new(3, 1, [0.0; 4]);
        img.set(2, 0, [3.0; 4]);
        let t = MipTexture::new(&img, true);
        assert_eq!(t.num_levels(), 2);
        assert!((t.bilinear(1, 0.5, 0.5, Wrap::Clamp)[0] - 1.0).abs() < 1e-6);
    }
}
