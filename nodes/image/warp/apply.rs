//! Applying a fitted map to an image: the map evaluated at every pixel centre (or on a coarse
//! grid and interpolated), then inverse mapping (sample the source at g(y)) or forward
//! mapping (move each source pixel to f(x)). Rows run in parallel (rayon).

use super::WarpMap;
use cgnodes_api::node::Choice;
use cgnodes_api::types::{Image, TRANSPARENT};
use rayon::prelude::*;

/// How the map moves the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mapping {
    /// Each output pixel samples the source bilinearly at g(centre), g(q_i) = p_i: no holes.
    Inverse,
    /// Each source pixel moves to the pixel under f(centre), f(p_i) = q_i: leaves holes.
    Forward,
}

impl Choice for Mapping {
    const CHOICES: &'static [(&'static str, Self)] =
        &[("inverse", Mapping::Inverse), ("forward", Mapping::Forward)];
}

/// How forward mapping's holes are filled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fill {
    /// Left transparent black.
    None,
    /// The colour of the nearest mapped pixel (breadth-first, 8-neighbours).
    Nearest,
    /// Push-pull: averages of mapped pixels over an image pyramid, pulled back down.
    PushPull,
}

impl Choice for Fill {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("none", Fill::None),
        ("nearest", Fill::Nearest),
        ("push_pull", Fill::PushPull),
    ];
}

/// The map at the centre of every pixel of a `w` x `h` image, row-major. `grid` = 0 evaluates
/// it at each centre; `grid` = N > 0 evaluates it at the grid corners (k N, l N) covering the
/// image and interpolates bilinearly, which is exact for affine maps.
pub fn eval_field(map: &dyn WarpMap, w: u32, h: u32, grid: u32) -> Vec<[f64; 2]> {
    let (wu, hu) = (w as usize, h as usize);
    let mut field = vec![[0.0; 2]; wu * hu];
    if wu == 0 || hu == 0 {
        return field;
    }
    if grid == 0 {
        field.par_chunks_mut(wu).enumerate().for_each(|(j, row)| {
            for (i, v) in row.iter_mut().enumerate() {
                *v = map.eval([i as f64 + 0.5, j as f64 + 0.5]);
            }
        });
        return field;
    }
    let n = grid as usize;
    let (gw, gh) = (wu.div_ceil(n) + 1, hu.div_ceil(n) + 1);
    let mut nodes = vec![[0.0; 2]; gw * gh];
    nodes.par_chunks_mut(gw).enumerate().for_each(|(l, row)| {
        for (k, v) in row.iter_mut().enumerate() {
            *v = map.eval([(k * n) as f64, (l * n) as f64]);
        }
    });
    let s = n as f64;
    field.par_chunks_mut(wu).enumerate().for_each(|(j, row)| {
        let gy = (j as f64 + 0.5) / s;
        let l = (gy.floor() as usize).min(gh - 2);
        let ty = gy - l as f64;
        for (i, v) in row.iter_mut().enumerate() {
            let gx = (i as f64 + 0.5) / s;
            let k = (gx.floor() as usize).min(gw - 2);
            let tx = gx - k as f64;
            let (a, b) = (nodes[l * gw + k], nodes[l * gw + k + 1]);
            let (c, d) = (nodes[(l + 1) * gw + k], nodes[(l + 1) * gw + k + 1]);
            for m in 0..2 {
                let top = a[m] + (b[m] - a[m]) * tx;
                let bottom = c[m] + (d[m] - c[m]) * tx;
                v[m] = top + (bottom - top) * ty;
            }
        }
    });
    field
}

/// Inverse mapping: output pixel k is `src` sampled bilinearly at `field[k]` (the source
/// position of its centre). Returns the image and the number of output pixels whose source
/// position lies outside `src` (transparent black).
pub fn warp_inverse(src: &Image, field: &[[f64; 2]]) -> (Image, usize) {
    let w = src.width as usize;
    let mut out = Image::new(src.width, src.height, TRANSPARENT);
    if w == 0 {
        return (out, 0);
    }
    let outside: usize = out
        .pixels
        .par_chunks_mut(w)
        .zip(field.par_chunks(w))
        .map(|(row, f)| {
            let mut miss = 0;
            for (o, x) in row.iter_mut().zip(f) {
                if src.contains(x[0], x[1]) {
                    *o = src.sample_bilinear(x[0], x[1]);
                } else {
                    miss += 1;
                }
            }
            miss
        })
        .sum();
    (out, outside)
}

/// Forward mapping: source pixel k goes to the output pixel containing `field[k]` (in
/// row-major order, so a later source pixel wins a collision). Returns the image and the
/// holes: output pixels nothing reached.
pub fn warp_forward(src: &Image, field: &[[f64; 2]]) -> (Image, Vec<bool>) {
    let (w, h) = (src.width as usize, src.height as usize);
    let mut out = Image::new(src.width, src.height, TRANSPARENT);
    let mut holes = vec![true; w * h];
    for (k, y) in field.iter().enumerate() {
        let (fx, fy) = (y[0].floor(), y[1].floor());
        // NaN fails both comparisons.
        if fx >= 0.0 && fy >= 0.0 && fx < w as f64 && fy < h as f64 {
            let t = fy as usize * w + fx as usize;
            out.pixels[t] = src.pixels[k];
            holes[t] = false;
        }
    }
    (out, holes)
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Affine([[f64; 3]; 2]);
    impl WarpMap for Affine {
        fn eval(&self, x: [f64; 2]) -> [f64; 2] {
            let m = &self.0;
            [
                m[0][0] * x[0] + m[0][1] * x[1] + m[0][2],
                m[1][0] * x[0] + m[1][1] * x[1] + m[1][2],
            ]
        }
    }

    #[test]
    fn grid_interpolation_is_exact_for_affine_maps() {
        let f = Affine([[1.1, 0.3, 2.0], [-0.2, 0.8, -1.0]]);
        let exact = eval_field(&f, 13, 7, 0);
        for n in [1, 2, 4, 5, 32] {
            let g = eval_field(&f, 13, 7, n);
            for (a, b) in exact.iter().zip(&g) {
                assert!((a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn forward_translation_by_whole_pixels_leaves_a_band_of_holes() {
        let mut src = Image::new(4, 3, [0.0; 4]);
        for (k, p) in src.pixels.iter_mut().enumerate() {
            *p = [k as f32, 0.0, 0.0, 1.0];
        }
        let f = Affine([[1.0, 0.0, 1.0], [0.0, 1.0, 0.0]]);
        let field = eval_field(&f, 4, 3, 0);
        let (out, holes) = warp_forward(&src, &field);
        for j in 0..3u32 {
            assert!(holes[j as usize * 4]);
            assert_eq!(out.get(0, j), TRANSPARENT);
            for i in 1..4u32 {
                assert_eq!(out.get(i, j), src.get(i - 1, j));
            }
        }
        // Inverse of the same shift: column 0's centres go to x = -0.5, outside the source.
        let g = Affine([[1.0, 0.0, -1.0], [0.0, 1.0, 0.0]]);
        let (out, outside) = warp_inverse(&src, &eval_field(&g, 4, 3, 0));
        assert_eq!(outside, 3);
        assert_eq!(out.get(2, 1), src.get(1, 1));
    }
}
