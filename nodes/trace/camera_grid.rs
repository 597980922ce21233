//! Camera rays' closest hits without the BVH. Every camera ray of a pinhole camera starts at
//! the eye and passes through a known pixel, so the triangles it can hit are those whose
//! projection overlaps that pixel: the hybrid renderers' rasterised primary visibility
//! (e.g. Barré-Brisebois et al. 2019, "Hybrid Rendering for Real-Time Ray Tracing", Ray
//! Tracing Gems ch. 25), made exact for a ray tracer. `CameraGrid::build` rasterises every
//! triangle conservatively into per-pixel candidate lists, each sorted by a lower bound of
//! the triangle's distance from the eye; `CameraGrid::intersect` runs the BVH's own
//! watertight test on a pixel's candidates, nearest first, and stops once the next one
//! starts beyond the closest hit. The answer is the BVH's closest hit (the same triangle
//! test on every triangle the ray can reach; where two triangles tie at the same distance,
//! either may be reported, as either may by the BVH).
//!
//! Triangles are clipped to the plane `z = z_near` in camera space before projecting. A
//! camera ray meets the part in front of that plane only inside a tiny pyramid at the eye;
//! triangles that reach into it are kept on a list every camera ray tests. Scenes whose
//! projected triangles would cover too many pixels (huge triangles over a huge film) get no
//! grid, and their camera rays take the BVH.

use super::bvh::{tri_test, Hit, RayPre};
use super::camera::{Frame, PinholeCamera};
use super::sampling::V3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

mod rays8;

/// Per-pixel candidate triangles of the camera rays.
#[derive(Clone, Debug)]
pub struct CameraGrid {
    width: u32,
    /// Start of each pixel's candidates in `cand` (`width * height + 1` entries).
    start: Vec<u32>,
    /// (lower bound of the eye's distance to the triangle, triangle), nearest first within
    /// each pixel.
    cand: Vec<(f32, u32)>,
    /// Triangles reaching into the pyramid in front of `z_near`: tested by every ray.
    near: Vec<u32>,
}

/// Room left around a pixel (in pixels) for the round-off of projecting in f64 and of the
/// f32 ray directions (about 1e-5 px at 16384 px).
const PIXEL_MARGIN: f64 = 0.02;

/// Film coordinates (pixels) beyond which a projected corner is not trusted: f64 places
/// an edge through such corners to about 1e-16 of their size, 1e-4 px here.
const FILM_LIMIT: f64 = 1e12;

/// The most triangles the list that every camera ray tests may hold; a scene with more
/// (triangles through the eye, or thrown far out) gets no grid.
const MAX_NEAR: usize = 64;

/// The part of the triangle `v` (camera space) with `z >= z0`: a convex polygon of 0, 3 or
/// 4 corners (Sutherland and Hodgman 1974, one plane), and its corner count.
fn clip_near(v: [[f64; 3]; 3], z0: f64) -> ([[f64; 3]; 4], usize) {
    let mut out = [[0.0; 3]; 4];
    let mut n = 0;
    for k in 0..3 {
        let (a, b) = (v[k], v[(k + 1) % 3]);
        let (ina, inb) = (a[2] >= z0, b[2] >= z0);
        if ina {
            out[n] = a;
            n += 1;
        }
        if ina != inb {
            let s = (z0 - a[2]) / (b[2] - a[2]);
            out[n] = [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), z0];
            n += 1;
        }
    }
    (out, n)
}

/// A convex polygon on the film: up to four corners.
#[derive(Clone, Copy, Debug)]
struct Poly {
    p: [[f64; 2]; 4],
    n: usize,
}

impl Poly {
    fn lo(&self, k: usize) -> f64 {
        self.p[..self.n]
            .iter()
            .map(|q| q[k])
            .fold(f64::INFINITY, f64::min)
    }
    fn hi(&self, k: usize) -> f64 {
        self.p[..self.n]
            .iter()
            .map(|q| q[k])
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

/// Pixels a convex film polygon may cover, grown by `PIXEL_MARGIN`: calls `f(pixel)` for
/// each pixel whose grown square the polygon overlaps (separating axes: the square's two
/// and the polygon's edge normals). A polygon of (almost) no area covers its bounds.
fn cover(poly: &Poly, size: (u32, u32), mut f: impl FnMut(usize)) {
    let (w, h) = (size.0 as f64, size.1 as f64);
    let m = PIXEL_MARGIN;
    let x0 = (poly.lo(0) - m).floor().max(0.0);
    let y0 = (poly.lo(1) - m).floor().max(0.0);
    let x1 = (poly.hi(0) + m).floor().min(w - 1.0);
    let y1 = (poly.hi(1) + m).floor().min(h - 1.0);
    if !(x0 <= x1 && y0 <= y1) {
        return;
    }
    // Edge lines `n . q + c >= 0` inside, for either winding.
    let (p, n) = (&poly.p, poly.n);
    let mut area = 0.0;
    for k in 0..n {
        let (a, b) = (p[k], p[(k + 1) % n]);
        area += a[0] * b[1] - b[0] * a[1];
    }
    let scale = (poly.hi(0) - poly.lo(0))
        .max(poly.hi(1) - poly.lo(1))
        .max(1.0);
    let mut edges = [(0.0f64, 0.0f64, 0.0f64); 4];
    let mut ne = 0;
    if area.abs() > 1e-9 * scale * scale {
        let sgn = area.signum();
        for k in 0..n {
            let (a, b) = (p[k], p[(k + 1) % n]);
            let (nx, ny) = (-(b[1] - a[1]) * sgn, (b[0] - a[0]) * sgn);
            edges[k] = (nx, ny, -(nx * a[0] + ny * a[1]));
        }
        ne = n;
    }
    for y in y0 as usize..=y1 as usize {
        for x in x0 as usize..=x1 as usize {
            let (sx0, sy0) = (x as f64 - m, y as f64 - m);
            let (sx1, sy1) = (x as f64 + 1.0 + m, y as f64 + 1.0 + m);
            let outside = edges[..ne].iter().any(|&(nx, ny, c)| {
                let qx = if nx > 0.0 { sx1 } else { sx0 };
                let qy = if ny > 0.0 { sy1 } else { sy0 };
                nx * qx + ny * qy + c < 0.0
            });
            if !outside {
                f(y * size.0 as usize + x);
            }
        }
    }
}

/// Lower bound of the distance from `e` to the box around triangle `t`, shrunk by a
/// relative 1e-4 so that the f32 hit distances of the triangle test stay above it.
fn eye_distance(e: [f64; 3], t: &[V3; 3]) -> f32 {
    let mut d2 = 0.0;
    for k in 0..3 {
        let lo = t.iter().map(|p| p[k] as f64).fold(f64::INFINITY, f64::min);
        let hi = t
            .iter()
            .map(|p| p[k] as f64)
            .fold(f64::NEG_INFINITY, f64::max);
        let g = (lo - e[k]).max(e[k] - hi).max(0.0);
        d2 += g * g;
    }
    (d2.sqrt() * (1.0 - 1e-4)) as f32
}

impl CameraGrid {
    /// Rasterises `tris` for the camera `cam`; `None` when the candidate lists would exceed
    /// eight entries per pixel plus a million (huge triangles over a huge film), when more
    /// than `MAX_NEAR` triangles would have to be tested by every ray, or when the scene is
    /// empty: the camera rays take the BVH then.
    pub fn build(tris: &[[V3; 3]], cam: &PinholeCamera) -> Option<CameraGrid> {
        let fr = cam.frame();
        let (w, h) = fr.size;
        let pixels = w as usize * h as usize;
        if tris.is_empty() {
            return None;
        }
        // The clipping plane: far below any distance that matters in the scene (1e-7 of its
        // extent from the eye), while the film positions behind it stay within about
        // 1e7 focal lengths, where f64 places a polygon's edges to far better than the
        // pixel margin.
        let ext = eye_extent(tris, fr.eye);
        if !ext.is_finite() {
            return None;
        }
        let z0 = (1e-7 * ext).max(f64::MIN_POSITIVE);
        // The pyramid in front of z0 that camera rays cross, as a box (with room).
        let half = [
            1.01 * z0 * 0.5 * w as f64 / fr.focal,
            1.01 * z0 * 0.5 * h as f64 / fr.focal,
        ];
        // Per chunk of triangles, in parallel: which reach into the pyramid in front of
        // z0, the film polygons of their parts behind z0 that lie on the film, and the
        // pixels those cover, each with the triangle's distance bound and index. A chunk
        // covers its polygons only while the polygons' film bounds (which bound their
        // pixel counts) summed over the chunks so far stay within the budget.
        let budget = 8 * pixels as u64 + 1_000_000;
        let used = AtomicU64::new(0);
        // Small scenes in small chunks too: a few large triangles cover most of the film.
        let size = (tris.len() / 64).clamp(1, CHUNK);
        let chunks: Vec<Option<Chunk>> = tris
            .par_chunks(size)
            .enumerate()
            .map(|(c, ts)| {
                let mut ch = Chunk::default();
                let mut polys = Vec::with_capacity(ts.len());
                let mut bound = 0u64;
                for (k, t) in ts.iter().enumerate() {
                    let i = (c * size + k) as u32;
                    let (near, poly) = project_triangle(t, &fr, z0, half);
                    if near {
                        ch.near.push(i);
                    }
                    if let Some(p) = poly {
                        bound += pixel_bound(&p, fr.size);
                        polys.push((i, p));
                    }
                }
                if used.fetch_add(bound, Ordering::Relaxed) + bound > budget {
                    return None;
                }
                for (i, p) in &polys {
                    let key = eye_distance(fr.eye, &tris[*i as usize]);
                    cover(p, fr.size, |px| ch.hits.push((px as u32, (key, *i))));
                }
                Some(ch)
            })
            .collect();
        let chunks: Vec<Chunk> = chunks.into_iter().collect::<Option<_>>()?;
        let near: Vec<u32> = chunks.iter().flat_map(|c| c.near.iter().copied()).collect();
        if near.len() > MAX_NEAR {
            return None;
        }
        // Sorted into compressed rows by pixel, stably (a counting sort), then each
        // pixel's candidates nearest first.
        let (start, mut cand) = rows_by_pixel(&chunks, pixels);
        sort_rows(&start, &mut cand);
        Some(CameraGrid {
            width: w,
            start,
            cand,
            near,
        })
    }

    /// The closest hit of the camera ray `eye + t dir`, `0 < t < tmax`, through film
    /// position (x + a, y + b) with 0 <= a, b <= 1, of the triangles `tris` the grid was
    /// built from, for the camera it was built for. `dir` is unit length.
    #[inline(always)]
    pub fn intersect(
        &self,
        tris: &[[V3; 3]],
        (x, y): (u32, u32),
        eye: V3,
        dir: V3,
        tmax: f32,
    ) -> Option<Hit> {
        let r = RayPre::new(eye, dir);
        let px = y as usize * self.width as usize + x as usize;
        let cand = &self.cand[self.start[px] as usize..self.start[px + 1] as usize];
        match r.axes() {
            (1, 2, 0) => self.closest::<1, 2, 0>(tris, &r, cand, tmax),
            (2, 1, 0) => self.closest::<2, 1, 0>(tris, &r, cand, tmax),
            (2, 0, 1) => self.closest::<2, 0, 1>(tris, &r, cand, tmax),
            (0, 2, 1) => self.closest::<0, 2, 1>(tris, &r, cand, tmax),
            (0, 1, 2) => self.closest::<0, 1, 2>(tris, &r, cand, tmax),
            _ => self.closest::<1, 0, 2>(tris, &r, cand, tmax),
        }
    }

    /// The closest hit among the near triangles and a pixel's candidates, with the ray's
    /// axis permutation fixed at compile time.
    #[inline(always)]
    fn closest<const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        tris: &[[V3; 3]],
        r: &RayPre,
        cand: &[(f32, u32)],
        mut tmax: f32,
    ) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        // Plain loops, not a shared closure: LLVM left the closure out of line, a call per
        // triangle built without the caller's AVX.
        for &i in &self.near {
            if let Some((t, u, v)) = tri_test::<KX, KY, KZ>(r, &tris[i as usize], tmax) {
                tmax = t;
                best = Some(Hit { t, prim: i, u, v });
            }
        }
        for &(key, i) in cand {
            if key >= tmax {
                break;
            }
            if let Some((t, u, v)) = tri_test::<KX, KY, KZ>(r, &tris[i as usize], tmax) {
                tmax = t;
                best = Some(Hit { t, prim: i, u, v });
            }
        }
        best
    }
}

/// The largest coordinate distance of a triangle corner from the eye (infinite when a
/// corner is; `f64::max` passes over NaN, and the tracer's scenes have finite corners).
fn eye_extent(tris: &[[V3; 3]], eye: [f64; 3]) -> f64 {
    let extent = |t: &[V3; 3]| {
        let mut ext = 0.0f64;
        for p in t {
            for (x, e) in p.iter().zip(eye) {
                ext = ext.max((*x as f64 - e).abs());
            }
        }
        ext
    };
    tris.par_iter().map(extent).reduce(|| 0.0, f64::max)
}

/// Whether triangle `t` reaches into the box `|x| <= half[0]`, `|y| <= half[1]`, `0 <= z <
/// z0` in front of the eye (where camera rays start and the film projection is imprecise),
/// and the film polygon of its part behind `z0` when that lies on the film.
fn project_triangle(t: &[V3; 3], fr: &Frame, z0: f64, half: [f64; 2]) -> (bool, Option<Poly>) {
    let (w, h) = fr.size;
    let v = t.map(|p| fr.view(p));
    let lo = |k: usize| v[0][k].min(v[1][k]).min(v[2][k]);
    let hi = |k: usize| v[0][k].max(v[1][k]).max(v[2][k]);
    let near = lo(2) < z0
        && hi(2) >= 0.0
        && lo(0) <= half[0]
        && hi(0) >= -half[0]
        && lo(1) <= half[1]
        && hi(1) >= -half[1];
    if hi(2) < z0 {
        return (near, None);
    }
    let (c, n) = clip_near(v, z0);
    let mut poly = Poly {
        p: [[0.0; 2]; 4],
        n,
    };
    for (q, c) in poly.p.iter_mut().zip(&c[..n]) {
        *q = fr.film(*c);
    }
    if n < 3 {
        return (near, None);
    }
    // Film positions too far out to place the edges precisely (or not finite):
    // the triangle goes on the list every ray tests.
    if poly.p[..n]
        .iter()
        .flatten()
        .any(|x| x.is_nan() || x.abs() > FILM_LIMIT)
    {
        return (true, None);
    }
    let on_film = poly.hi(0) >= -1.0
        && poly.lo(0) <= w as f64 + 1.0
        && poly.hi(1) >= -1.0
        && poly.lo(1) <= h as f64 + 1.0;
    (near, on_film.then_some(poly))
}

/// What one chunk of triangles adds to the grid: its triangles that every ray tests, and
/// (pixel, (distance bound, triangle)) per covered pixel, in triangle order.
#[derive(Default)]
struct Chunk {
    near: Vec<u32>,
    hits: Vec<(u32, (f32, u32))>,
}

/// Triangles per chunk of the grid's build, at most.
const CHUNK: usize = 4096;

/// An upper bound of the pixels `cover` visits for `p`: its film bounds grown by a pixel.
fn pixel_bound(p: &Poly, (w, h): (u32, u32)) -> u64 {
    let (x0, x1) = (p.lo(0).max(0.0), p.hi(0).min(w as f64));
    let (y0, y1) = (p.lo(1).max(0.0), p.hi(1).min(h as f64));
    let n = (x1 - x0 + 2.0).max(0.0) * (y1 - y0 + 2.0).max(0.0);
    n.min(w as f64 * h as f64) as u64
}

/// The chunks' hits sorted into compressed rows by pixel, stably (a counting sort): row
/// starts and the candidates, each pixel's in triangle order.
fn rows_by_pixel(chunks: &[Chunk], pixels: usize) -> (Vec<u32>, Vec<(f32, u32)>) {
    let hits = || chunks.iter().flat_map(|c| c.hits.iter());
    let mut start = vec![0u32; pixels + 1];
    for &(px, _) in hits() {
        start[px as usize + 1] += 1;
    }
    for k in 0..pixels {
        start[k + 1] += start[k];
    }
    let mut fill = start.clone();
    let mut cand = vec![(0.0f32, 0u32); start[pixels] as usize];
    for &(px, c) in hits() {
        cand[fill[px as usize] as usize] = c;
        fill[px as usize] += 1;
    }
    (start, cand)
}

/// Pixels whose candidates one job of `sort_rows` sorts.
const SORT_PIXELS: usize = 256;

/// Sorts each pixel's candidates nearest first (ties by triangle), runs of pixels in
/// parallel.
fn sort_rows(start: &[u32], cand: &mut [(f32, u32)]) {
    let pixels = start.len() - 1;
    let mut runs = Vec::with_capacity(pixels.div_ceil(SORT_PIXELS));
    let mut rest = cand;
    for p0 in (0..pixels).step_by(SORT_PIXELS) {
        let st = &start[p0..=(p0 + SORT_PIXELS).min(pixels)];
        let (run, tail) = rest.split_at_mut((st[st.len() - 1] - st[0]) as usize);
        runs.push((st, run));
        rest = tail;
    }
    runs.into_par_iter().for_each(|(st, run)| {
        for w in st.windows(2) {
            run[(w[0] - st[0]) as usize..(w[1] - st[0]) as usize]
                .sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        }
    });
}

#[cfg(test)]
mod tests;
