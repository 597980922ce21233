//! Triangle rasterization with a z-buffer, in 2D homogeneous coordinates.
//!
//! Following Olano and Greer, "Triangle Scan Conversion using 2D Homogeneous Coordinates"
//! (Graphics Hardware 1997): with the vertices' homogeneous screen coordinates
//! `h_i = (X_i, Y_i, W_i)` (pixel = `(X/W, Y/W)`) as the columns of `M`, the rows of
//! `M^-1` are three edge functions, linear in the pixel `(x, y)`:
//! `e = M^-1 (x, y, 1)`. A pixel is covered when all `e_i >= 0` (and `sum e > 0`), and
//! `b = e / sum(e)` are the *perspective-correct* barycentric coordinates of the surface
//! point seen through it, so any attribute that is linear on the triangle in 3-D (world
//! position, view depth, UV) interpolates exactly as `sum b_i a_i`. No clipping is needed
//! for coverage; the near plane is a depth test, and the bounding box is taken from the
//! triangle clipped to `W >= w_near`.
//!
//! The image is split into horizontal bands; triangles are binned to bands in order and
//! the bands are filled in parallel (rayon), each in triangle order, so the result does
//! not depend on the thread count.

use cgnodes_api::types::vec3::{cross, dot};
use rayon::prelude::*;

/// A triangle ready to rasterize: edge functions, depths and pixel bounds.
#[derive(Clone, Copy, Debug)]
pub struct TriSetup {
    /// Rows of `M^-1`: `e_i = inv[i][0] x + inv[i][1] y + inv[i][2]`.
    pub inv: [[f64; 3]; 3],
    /// The depth attribute at the corners (linear on the triangle in 3-D).
    pub depth: [f64; 3],
    /// Pixel bounds `[x0, y0, x1, y1)`, clamped to the image.
    pub bbox: [u32; 4],
    /// `det M < 0`; with the camera convention of `render`, a counter-clockwise (front) face.
    pub det_negative: bool,
}

/// Sets a triangle up from homogeneous screen coordinates `h` and corner depths. Returns
/// `None` when it is degenerate (edge-on, through the eye) or lies wholly outside the image
/// or behind `W = w_near`.
pub fn setup_triangle(
    h: [[f64; 3]; 3],
    depth: [f64; 3],
    w_near: f64,
    width: u32,
    height: u32,
) -> Option<TriSetup> {
    let c12 = cross(h[1], h[2]);
    let det = dot(h[0], c12);
    let scale = (dot(h[0], h[0]) * dot(h[1], h[1]) * dot(h[2], h[2])).sqrt();
    if det.is_nan() || det.abs() <= 1e-14 * scale || !det.is_finite() {
        return None;
    }
    let inv = [
        c12.map(|v| v / det),
        cross(h[2], h[0]).map(|v| v / det),
        cross(h[0], h[1]).map(|v| v / det),
    ];
    // Bounding box of the triangle clipped to W >= w_near (Sutherland-Hodgman, one plane).
    let mut x0 = f64::INFINITY;
    let mut y0 = f64::INFINITY;
    let mut x1 = f64::NEG_INFINITY;
    let mut y1 = f64::NEG_INFINITY;
    let mut add = |p: [f64; 3]| {
        let (x, y) = (p[0] / p[2], p[1] / p[2]);
        x0 = x0.min(x);
        y0 = y0.min(y);
        x1 = x1.max(x);
        y1 = y1.max(y);
    };
    for i in 0..3 {
        let a = h[i];
        let b = h[(i + 1) % 3];
        let ina = a[2] >= w_near;
        let inb = b[2] >= w_near;
        if ina {
            add(a);
        }
        if ina != inb {
            let t = (w_near - a[2]) / (b[2] - a[2]);
            add([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), w_near]);
        }
    }
    if !(x0.is_finite() && y0.is_finite() && x1.is_finite() && y1.is_finite()) {
        return None;
    }
    // Pixel centres sit at (i + 0.5): pixel i may be covered when x0 - 0.5 <= i <= x1 - 0.5.
    let bx0 = (x0 - 0.5).ceil().max(0.0);
    let by0 = (y0 - 0.5).ceil().max(0.0);
    let bx1 = ((x1 - 0.5).floor() + 1.0).min(width as f64);
    let by1 = ((y1 - 0.5).floor() + 1.0).min(height as f64);
    if bx0 >= bx1 || by0 >= by1 {
        return None;
    }
    Some(TriSetup {
        inv,
        depth,
        bbox: [bx0 as u32, by0 as u32, bx1 as u32, by1 as u32],
        det_negative: det < 0.0,
    })
}

/// Perspective-correct barycentric coordinates of the surface point seen at `(x, y)`
/// (extrapolated outside the triangle), or `None` through the triangle's horizon.
#[inline]
pub fn barycentric(inv: &[[f64; 3]; 3], x: f64, y: f64) -> Option<[f64; 3]> {
    let e = inv.map(|r| r[0] * x + r[1] * y + r[2]);
    let s = e[0] + e[1] + e[2];
    if s.abs() < 1e-300 || !s.is_finite() {
        return None;
    }
    let r = 1.0 / s;
    Some(e.map(|v| v * r))
}

/// A z-buffer and the index of the nearest triangle at each pixel (`u32::MAX` = empty).
pub struct DepthTarget {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Nearest depth per pixel (`f32::INFINITY` where empty).
    pub depth: Vec<f32>,
    /// Triangle index per pixel (empty when ids were not requested).
    pub ids: Vec<u32>,
}

/// Rows per band of the parallel rasterizer.
const BAND: u32 = 16;

/// Bins triangles to horizontal bands of `band` rows by their bounding boxes, in
/// triangle order. Chunks of triangles are binned in parallel and each band's lists are
/// joined in chunk order, so the bins are the same as a sequential pass.
pub fn bin_rows(tris: &[Option<TriSetup>], height: u32, band: u32) -> Vec<Vec<u32>> {
    const CHUNK: usize = 1 << 14;
    let nb = height.div_ceil(band) as usize;
    let parts: Vec<Vec<Vec<u32>>> = tris
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(ci, chunk)| {
            let mut bins: Vec<Vec<u32>> = vec![Vec::new(); nb];
            for (i, t) in chunk.iter().enumerate() {
                if let Some(t) = t {
                    let b0 = (t.bbox[1] / band) as usize;
                    let b1 = ((t.bbox[3] - 1) / band) as usize;
                    for bin in &mut bins[b0.min(nb)..=b1.min(nb - 1)] {
                        bin.push((ci * CHUNK + i) as u32);
                    }
                }
            }
            bins
        })
        .collect();
    (0..nb)
        .into_par_iter()
        .map(|b| {
            let mut v = Vec::with_capacity(parts.iter().map(|p| p[b].len()).sum());
            for p in &parts {
                v.extend_from_slice(&p[b]);
            }
            v
        })
        .collect()
}

/// Triangles whose bounding box is wider than this many pixels are walked along each row's
/// span (`row_span`) rather than across the whole box; narrower ones are cheaper to test.
const SPAN_MIN_WIDTH: u32 = 12;

/// A conservative span `[x0, x1)` of row pixels that may be covered, within the box columns
/// `[bx0, bx1)`, for edge functions `e_i(x) = ax[i] (x + 0.5) + ey[i]`: each edge with
/// `ax > 0` bounds the row on the left at `x >= -ey/ax - 0.5`, one with `ax < 0` on the
/// right; an edge parallel to the rows (`ax = 0`) with `ey < 0` empties it. The bounds are
/// widened by two pixels (truncation instead of floor, and rounding) and every pixel in
/// the span is still tested exactly, so coverage is the same as testing the whole box.
#[inline]
fn row_span(bx0: u32, bx1: u32, ax: [f64; 3], ey: [f64; 3]) -> (u32, u32) {
    let (mut lo, mut hi) = (bx0 as i64, bx1 as i64);
    for k in 0..3 {
        let v = -ey[k] / ax[k] - 0.5;
        if ax[k] > 0.0 {
            if !v.is_nan() {
                lo = lo.max((v as i64).saturating_sub(2));
            }
        } else if ax[k] < 0.0 {
            if !v.is_nan() {
                hi = hi.min((v as i64).saturating_add(2));
            }
        } else if ey[k] < 0.0 {
            return (bx0, bx0);
        }
    }
    if lo >= hi {
        (bx0, bx0)
    } else {
        (lo as u32, hi as u32)
    }
}

/// Rasterizes the triangles listed in `list` into rows `y_start..y_end` of a z-buffer
/// `width` wide (`depth` and `ids` hold just those rows), keeping the smallest depth in
/// `[zmin, zmax]`; ties keep the earlier triangle.
#[allow(clippy::too_many_arguments)]
pub fn fill_rows(
    tris: &[Option<TriSetup>],
    list: &[u32],
    y_start: u32,
    y_end: u32,
    width: u32,
    zmin: f64,
    zmax: f64,
    depth: &mut [f32],
    mut ids: Option<&mut [u32]>,
) {
    let w = width as usize;
    for &ti in list {
        let Some(t) = tris[ti as usize].as_ref() else {
            continue;
        };
        let ya = t.bbox[1].max(y_start);
        let yb = t.bbox[3].min(y_end);
        let [a, b, c] = t.inv;
        let d = t.depth;
        let wide = t.bbox[2] - t.bbox[0] > SPAN_MIN_WIDTH;
        for y in ya..yb {
            let yc = y as f64 + 0.5;
            let row = (y - y_start) as usize * w;
            let ey = [a[1] * yc + a[2], b[1] * yc + b[2], c[1] * yc + c[2]];
            let (x0, x1) = if wide {
                row_span(t.bbox[0], t.bbox[2], [a[0], b[0], c[0]], ey)
            } else {
                (t.bbox[0], t.bbox[2])
            };
            for x in x0..x1 {
                let xc = x as f64 + 0.5;
                let e0 = a[0] * xc + ey[0];
                let e1 = b[0] * xc + ey[1];
                let e2 = c[0] * xc + ey[2];
                if e0 < 0.0 || e1 < 0.0 || e2 < 0.0 {
                    continue;
                }
                let s = e0 + e1 + e2;
                if s <= 0.0 {
                    continue;
                }
                let z = (e0 * d[0] + e1 * d[1] + e2 * d[2]) / s;
                if !(z >= zmin && z <= zmax) {
                    continue;
                }
                let k = row + x as usize;
                let zf = z as f32;
                if zf < depth[k] {
                    depth[k] = zf;
                    if let Some(ic) = ids.as_deref_mut() {
                        ic[k] = ti;
                    }
                }
            }
        }
    }
}

/// Rasterizes triangles (index = position in `tris`; `None` entries are skipped) into a
/// z-buffer keeping the smallest depth within `[zmin, zmax]`; ties keep the earlier
/// triangle. `keep_ids` also records the winning triangle per pixel.
pub fn rasterize(
    tris: &[Option<TriSetup>],
    width: u32,
    height: u32,
    zmin: f64,
    zmax: f64,
    keep_ids: bool,
) -> DepthTarget {
    rasterize_into(tris, width, height, zmin, zmax, keep_ids, Vec::new())
}

/// `rasterize` writing the depths into `depth` (cleared and refilled; a buffer reused
/// from an earlier render is written without new page faults).
pub(super) fn rasterize_into(
    tris: &[Option<TriSetup>],
    width: u32,
    height: u32,
    zmin: f64,
    zmax: f64,
    keep_ids: bool,
    mut depth: Vec<f32>,
) -> DepthTarget {
    let bins = bin_rows(tris, height, BAND);
    let w = width as usize;
    depth.clear();
    depth.resize(w * height as usize, f32::INFINITY);
    let mut ids = if keep_ids {
        vec![u32::MAX; w * height as usize]
    } else {
        Vec::new()
    };
    let band_len = w * BAND as usize;
    let rows = |bi: usize| (bi as u32 * BAND, ((bi as u32 + 1) * BAND).min(height));
    if keep_ids {
        depth
            .par_chunks_mut(band_len)
            .zip(ids.par_chunks_mut(band_len))
            .enumerate()
            .for_each(|(bi, (dc, ic))| {
                let (y0, y1) = rows(bi);
                fill_rows(tris, &bins[bi], y0, y1, width, zmin, zmax, dc, Some(ic))
            });
    } else {
        depth
            .par_chunks_mut(band_len)
            .enumerate()
            .for_each(|(bi, dc)| {
                let (y0, y1) = rows(bi);
                fill_rows(tris, &bins[bi], y0, y1, width, zmin, zmax, dc, None)
            });
    }
    DepthTarget {
        width,
        height,
        depth,
        ids,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An affine (W = 1) triangle in pixel coordinates.
    fn flat(p: [[f64; 2]; 3], z: [f64; 3]) -> Option<TriSetup> {
        setup_triangle(p.map(|q| [q[0], q[1], 1.0]), z, 0.5, 16, 16)
    }

    #[test]
    fn coverage_counts_pixel_centres_inside() {
        // Right triangle with legs of 8 pixels along the axes from (0,0): pixel centres
        // (i+.5, j+.5) with i + j + 1 <= 8 are inside: 8 + 7 + ... + 1 = 36 pixels.
        let t = flat([[0.0, 0.0], [8.0, 0.0], [0.0, 8.0]], [1.0; 3]);
        let r = rasterize(&[t], 16, 16, 0.0, 10.0, true);
        let covered = r.ids.iter().filter(|&&i| i == 0).count();
        assert_eq!(covered, 36);
        assert_eq!(r.ids[0], 0);
        assert_eq!(r.ids[7], 0); // (7.5, 0.5): 8 - 0.5 - 7.5 = 0 on the edge
        assert_eq!(r.ids[8], u32::MAX);
    }

    #[test]
    fn depth_is_interpolated_and_nearest_wins() {
        // A plane z = 1 + x/16 over the whole 16x16 image, and a nearer small triangle.
        let big = flat([[0.0, 0.0], [32.0, 0.0], [0.0, 32.0]], [1.0, 3.0, 1.0]);
        let small = flat([[2.0, 2.0], [6.0, 2.0], [2.0, 6.0]], [0.5; 3]);
        let far = flat([[2.0, 2.0], [6.0, 2.0], [2.0, 6.0]], [5.0; 3]);
        let r = rasterize(&[big, far, small], 16, 16, 0.0, 10.0, true);
        let d = r.depth[10 * 16 + 9];
        assert!((d as f64 - (1.0 + 9.5 / 16.0)).abs() < 1e-6);
        assert_eq!(r.ids[2 * 16 + 2], 2);
        assert_eq!(r.depth[2 * 16 + 2], 0.5);
        // The far triangle is hidden everywhere.
        assert!(r.ids.iter().all(|&i| i != 1));
    }

    #[test]
    fn perspective_correct_barycentrics() {
        // A triangle in 3-D seen by a camera with focal length 10 and centre (8, 8):
        // corners at depths 1, 2 and 4. The surface point at b = (1/3, 1/3, 1/3) has
        // depth 7/3; its screen position is the projection of that 3-D point.
        let v = [[0.0, 0.0, 1.0], [1.0, 0.0, 2.0], [0.0, 1.0, 4.0]];
        let h = v.map(|p| [8.0 * p[2] + 10.0 * p[0], 8.0 * p[2] - 10.0 * p[1], p[2]]);
        let t = setup_triangle(h, [1.0, 2.0, 4.0], 0.01, 16, 16).unwrap();
        let c = [1.0 / 3.0, 1.0 / 3.0, 7.0 / 3.0];
        let (x, y) = (8.0 + 10.0 * c[0] / c[2], 8.0 - 10.0 * c[1] / c[2]);
        let b = barycentric(&t.inv, x, y).unwrap();
        for bk in b {
            assert!((bk - 1.0 / 3.0).abs() < 1e-12);
        }
        // Screen-space (affine) interpolation would give a different depth here.
        let z = b[0] * 1.0 + b[1] * 2.0 + b[2] * 4.0;
        assert!((z - 7.0 / 3.0).abs() < 1e-12);
    }

    #[test]
    fn triangle_through_the_near_plane_is_clipped_by_depth() {
        // Corners behind and in front of the eye: coverage stops at depth >= near.
        let v = [[-1.0, 0.5, -1.0], [1.0, 0.5, -1.0], [0.0, 0.5, 5.0]];
        let h = v.map(|p| [8.0 * p[2] + 4.0 * p[0], 8.0 * p[2] - 4.0 * p[1], p[2]]);
        let t = setup_triangle(h, v.map(|p| p[2]), 0.1, 16, 16);
        let r = rasterize(&[t], 16, 16, 0.1, 100.0, true);
        assert!(r.ids.contains(&0));
        assert!(r.depth.iter().all(|&d| d == f32::INFINITY || d >= 0.1));
    }

    /// The old fill: every pixel of the bounding box tested (the reference for `row_span`).
    fn fill_box(
        t: &TriSetup,
        width: u32,
        zmin: f64,
        zmax: f64,
        depth: &mut [f32],
        ids: &mut [u32],
    ) {
        let [a, b, c] = t.inv;
        for y in t.bbox[1]..t.bbox[3] {
            for x in t.bbox[0]..t.bbox[2] {
                let (xc, yc) = (x as f64 + 0.5, y as f64 + 0.5);
                let e = [a, b, c].map(|r| r[0] * xc + (r[1] * yc + r[2]));
                let s = e[0] + e[1] + e[2];
                if e.iter().any(|&v| v < 0.0) || s <= 0.0 {
                    continue;
                }
                let z = (e[0] * t.depth[0] + e[1] * t.depth[1] + e[2] * t.depth[2]) / s;
                let k = (y * width + x) as usize;
                if z >= zmin && z <= zmax && (z as f32) < depth[k] {
                    depth[k] = z as f32;
                    ids[k] = 0;
                }
            }
        }
    }

    #[test]
    fn row_spans_cover_the_same_pixels_as_the_box() {
        // Wide slivers, perspective triangles through the near plane and horizontal edges,
        // at 64x48: the span walk must give bit-identical depth and coverage.
        let (w, h) = (64u32, 48u32);
        let mut state = 12345u64;
        let mut rnd = || cgnodes_api::rng::lcg_next(&mut state);
        let mut checked = 0;
        for i in 0..400 {
            let hv: [[f64; 3]; 3] = std::array::from_fn(|_| {
                let wv = if i % 3 == 0 { 0.2 + 2.0 * rnd() } else { 1.0 };
                let wv = if i % 7 == 0 { wv - 0.8 } else { wv };
                [(rnd() * 120.0 - 28.0) * wv, (rnd() * 90.0 - 21.0) * wv, wv]
            });
            let mut hv = hv;
            if i % 5 == 0 {
                hv[1][1] = hv[0][1] / hv[0][2] * hv[1][2]; // an edge along a row
            }
            let Some(t) = setup_triangle(hv, [1.0, 2.0, 3.0], 0.1, w, h) else {
                continue;
            };
            let n = (w * h) as usize;
            let (mut d0, mut i0) = (vec![f32::INFINITY; n], vec![u32::MAX; n]);
            fill_box(&t, w, 0.0, 1e9, &mut d0, &mut i0);
            let (mut d1, mut i1) = (vec![f32::INFINITY; n], vec![u32::MAX; n]);
            fill_rows(&[Some(t)], &[0], 0, h, w, 0.0, 1e9, &mut d1, Some(&mut i1));
            assert_eq!(i0, i1, "triangle {i}: {hv:?}");
            assert_eq!(d0, d1, "triangle {i}");
            if t.bbox[2] - t.bbox[0] > SPAN_MIN_WIDTH && i0.contains(&0) {
                checked += 1;
            }
        }
        assert!(checked > 50, "only {checked} wide covered triangles");
    }

    #[test]
    fn parallel_binning_matches_a_sequential_pass() {
        // More triangles than one binning chunk (2^14), some culled (None), spanning one or
        // several bands: every band lists its triangles once each, in index order.
        let tris: Vec<Option<TriSetup>> = (0..40_000u32)
            .map(|i| {
                let y = (i * 7919 % 60) as f64;
                let hgt = 1.0 + (i % 23) as f64;
                let p = [[1.0, y, 1.0], [9.0, y, 1.0], [1.0, y + hgt, 1.0]];
                (i % 11 != 0).then(|| setup_triangle(p, [1.0; 3], 0.5, 16, 64))?
            })
            .collect();
        let bins = bin_rows(&tris, 64, 8);
        let mut expect: Vec<Vec<u32>> = vec![Vec::new(); 8];
        for (i, t) in tris.iter().enumerate() {
            if let Some(t) = t {
                for (b, bin) in expect.iter_mut().enumerate() {
                    let (y0, y1) = (b as u32 * 8, b as u32 * 8 + 8);
                    if t.bbox[1] < y1 && t.bbox[3] > y0 {
                        bin.push(i as u32);
                    }
                }
            }
        }
        assert!(expect.iter().all(|b| b.len() > 1000));
        assert_eq!(bins, expect);
    }

    #[test]
    fn same_result_with_any_thread_count() {
        let tris: Vec<_> = (0..50)
            .map(|i| {
                let o = (i % 7) as f64;
                flat(
                    [[o, 0.3 * i as f64 % 16.0], [o + 9.0, 2.0], [3.0, o + 10.0]],
                    [i as f64 * 0.1, 1.0, 2.0],
                )
            })
            .collect();
        let a = rasterize(&tris, 16, 16, 0.0, 10.0, true);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let b = pool.install(|| rasterize(&tris, 16, 16, 0.0, 10.0, true));
        assert_eq!(a.ids, b.ids);
        assert_eq!(a.depth, b.depth);
    }
}
