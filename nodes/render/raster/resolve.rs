//! The rasterizer's band stage, rasterization fused with resolve: each band of `BAND_PX`
//! pixel rows is rasterized into a small visibility buffer (nearest depth and triangle per
//! sample) and resolved right away, so the full-resolution sample buffer never exists.
//! Resolve shades every sample (`ssaa`) or each triangle once per pixel at the centroid of
//! the samples it covers, weighted by its coverage (`msaa`), and takes the passes from the
//! pixel's nearest triangle.

use super::options::{AntiAliasing, RasterOptions, RenderOutput};
use super::rasterize::fill_rows;
use super::shader::Shader;
use cgnodes_api::prelude::*;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Pixel rows per band.
pub(super) const BAND_PX: usize = 8;

/// Pixel columns per block: a band is resolved block by block.
const BLOCK_PX: usize = 16;

/// Rasterizes and resolves every band of `bins` (triangles per band of `BAND_PX * s` sample
/// rows) through `cam` at `s x s` samples per pixel; `triangles` is passed through to the
/// output's count.
pub(super) fn resolve_bands(
    sh: &Shader,
    bins: &[Vec<u32>],
    cam: &Camera,
    s: u32,
    opts: &RasterOptions,
    triangles: usize,
) -> RenderOutput {
    let (w, h) = (cam.width, cam.height);
    let (ws, hs) = (w * s, h * s);
    let passes = opts.passes;
    let lit = passes.color;
    let band_rows = BAND_PX as u32 * s;
    let setups = sh.setups;
    let npx = w as usize * h as usize;
    let zero = [0.0f32; 4];
    let bg = [
        opts.background[0] as f32,
        opts.background[1] as f32,
        opts.background[2] as f32,
        1.0,
    ];
    // Only the passes asked for get a buffer.
    let alloc = |on: bool, v: [f32; 4]| if on { vec![v; npx] } else { Vec::new() };
    // Zeroed buffers are allocated lazily by the system; the bands write every colour
    // pixel (the background where nothing is hit), in parallel.
    let mut color = alloc(passes.color, zero);
    let mut depth = alloc(passes.depth, zero);
    let mut normal = alloc(passes.normal, zero);
    let mut position = alloc(passes.position, zero);
    let mut uvp = alloc(passes.uv, zero);
    let mut basep = alloc(passes.base_color, zero);
    let shaded = AtomicU64::new(0);
    let wu = w as usize;
    let n_samples = (s * s) as f64;
    let band_len = wu * BAND_PX;
    let band_samples = ws as usize * band_rows as usize;
    let nbands = bins.len();
    type Px = [f32; 4];
    // Each band's slice of every produced pass (`None` for passes not produced).
    let surface_passes = passes.any_surface();
    if lit || surface_passes {
        let mut chunks: Vec<std::vec::IntoIter<Option<&mut [Px]>>> = [
            &mut color,
            &mut depth,
            &mut normal,
            &mut position,
            &mut uvp,
            &mut basep,
        ]
        .into_iter()
        .map(|buf| {
            let v: Vec<Option<&mut [Px]>> = if buf.is_empty() {
                (0..nbands).map(|_| None).collect()
            } else {
                buf.chunks_mut(band_len).map(Some).collect()
            };
            v.into_iter()
        })
        .collect();
        let bands: Vec<[Option<&mut [Px]>; 6]> = (0..nbands)
            .map(|_| std::array::from_fn(|k| chunks[k].next().flatten()))
            .collect();
        let bands_done = std::sync::atomic::AtomicUsize::new(0);
        bands.into_par_iter().enumerate().for_each_init(
            || {
                // (triangle, covered samples, sum of sample x, sum of sample y, min depth)
                let groups: Vec<(u32, u32, f64, f64, f32)> = Vec::with_capacity(16);
                (Vec::new(), Vec::new(), groups)
            },
            |(zbuf, ibuf, groups), (bi, mut out)| {
                zbuf.clear();
                zbuf.resize(band_samples, f32::INFINITY);
                ibuf.clear();
                ibuf.resize(band_samples, u32::MAX);
                let y_start = bi as u32 * band_rows;
                let y_end = (y_start + band_rows).min(hs);
                fill_rows(
                    setups,
                    &bins[bi],
                    y_start,
                    y_end,
                    ws,
                    cam.near,
                    cam.far,
                    zbuf,
                    Some(ibuf),
                );
                let mut count = 0u64;
                let rows = (y_end - y_start) as usize / s as usize;
                let (sz, wsu) = (s as usize, ws as usize);
                let ssaa = lit && opts.aa == AntiAliasing::Supersampling;
                let msaa = lit && opts.aa == AntiAliasing::Multisampling;
                // Blocks of BLOCK_PX columns, row by row inside each: the triangles and
                // shadow-map texels a block reads stay in cache from one row to the next.
                for (xb, r) in (0..wu)
                    .step_by(BLOCK_PX)
                    .flat_map(|xb| (0..rows).map(move |r| (xb, r)))
                {
                    let py = bi * BAND_PX + r;
                    // Sample row of the pixel row's first sample, relative to the band.
                    let row0 = r * sz * wsu;
                    for px in xb..(xb + BLOCK_PX).min(wu) {
                        groups.clear();
                        let mut acc = [0.0f64; 3];
                        let mut empty = 0u32;
                        let k0 = row0 + px * sz;
                        let first = ibuf[k0];
                        // Fast path: every sample on one triangle (most pixels). The sums run
                        // in the same order as the general loop, so the result is the same.
                        let uniform = !ssaa
                            && first != u32::MAX
                            && (0..sz).all(|j| {
                                let k = k0 + j * wsu;
                                ibuf[k..k + sz].iter().all(|&id| id == first)
                            });
                        if uniform {
                            let (mut gx, mut gy, mut gd) = (0.0f64, 0.0f64, f32::INFINITY);
                            for j in 0..sz {
                                let yc = (py * sz + j) as f64 + 0.5;
                                let k = k0 + j * wsu;
                                for (i, &d) in zbuf[k..k + sz].iter().enumerate() {
                                    gx += (px * sz + i) as f64 + 0.5;
                                    gy += yc;
                                    gd = gd.min(d);
                                }
                            }
                            groups.push((first, (sz * sz) as u32, gx, gy, gd));
                        } else {
                            for j in 0..sz {
                                let sy = py * sz + j;
                                for i in 0..sz {
                                    let sx = px * sz + i;
                                    let k = k0 + j * wsu + i;
                                    let id = ibuf[k];
                                    if id == u32::MAX {
                                        empty += 1;
                                        continue;
                                    }
                                    let (xc, yc) = (sx as f64 + 0.5, sy as f64 + 0.5);
                                    if ssaa {
                                        if let Some(sf) = sh.surface(id as usize, xc, yc, 1.0, true)
                                        {
                                            count += 1;
                                            for (a, c) in acc.iter_mut().zip(sf.color) {
                                                *a += c;
                                            }
                                        }
                                    }
                                    let d = zbuf[k];
                                    match groups.iter_mut().find(|g| g.0 == id) {
                                        Some(g) => {
                                            g.1 += 1;
                                            g.2 += xc;
                                            g.3 += yc;
                                            g.4 = g.4.min(d);
                                        }
                                        None => groups.push((id, 1, xc, yc, d)),
                                    }
                                }
                            }
                        }
                        if groups.is_empty() {
                            if let Some(c) = out[0].as_deref_mut() {
                                c[r * wu + px] = bg;
                            }
                            continue;
                        }
                        // The nearest triangle in the pixel (first on ties) gives the passes.
                        let mut nearest = 0;
                        for (gi, gr) in groups.iter().enumerate() {
                            if gr.4 < groups[nearest].4 {
                                nearest = gi;
                            }
                        }
                        let step = s as f64;
                        let mut pass_surf = None;
                        for (gi, gr) in groups.iter().enumerate() {
                            let (x, y) = (gr.2 / gr.1 as f64, gr.3 / gr.1 as f64);
                            if msaa {
                                if let Some(sf) = sh.surface(gr.0 as usize, x, y, step, true) {
                                    count += 1;
                                    for (a, c) in acc.iter_mut().zip(sf.color) {
                                        *a += c * gr.1 as f64;
                                    }
                                    if gi == nearest && surface_passes {
                                        pass_surf = Some(sf);
                                    }
                                }
                            } else if gi == nearest && surface_passes {
                                pass_surf = sh.surface(gr.0 as usize, x, y, step, false);
                            }
                        }
                        let o = r * wu + px;
                        if let Some(c) = out[0].as_deref_mut() {
                            for (a, c) in acc.iter_mut().zip(opts.background) {
                                *a += c * empty as f64;
                            }
                            c[o] = [
                                (acc[0] / n_samples) as f32,
                                (acc[1] / n_samples) as f32,
                                (acc[2] / n_samples) as f32,
                                1.0,
                            ];
                        }
                        let Some(sf) = pass_surf else {
                            continue;
                        };
                        let f3 = |v: [f64; 3]| [v[0] as f32, v[1] as f32, v[2] as f32, 1.0];
                        let d = sf.depth as f32;
                        let vals = [
                            [d, d, d, 1.0],
                            f3(sf.n),
                            f3(sf.p),
                            [sf.uv[0] as f32, sf.uv[1] as f32, 0.0, 1.0],
                            f3(sf.base),
                        ];
                        for (band, v) in out[1..].iter_mut().zip(vals) {
                            if let Some(b) = band.as_deref_mut() {
                                b[o] = v;
                            }
                        }
                    }
                }
                shaded.fetch_add(count, Ordering::Relaxed);
                let k = bands_done.fetch_add(1, Ordering::Relaxed) + 1;
                (sh.progress)(k as f64 / nbands as f64);
            },
        );
    }
    let img = |pixels: Vec<Px>| {
        if pixels.is_empty() {
            Image {
                width: 0,
                height: 0,
                pixels,
            }
        } else {
            Image {
                width: w,
                height: h,
                pixels,
            }
        }
    };
    RenderOutput {
        color: img(color),
        depth: img(depth),
        normal: img(normal),
        position: img(position),
        uv: img(uvp),
        base_color: img(basep),
        triangles,
        shaded: shaded.into_inner(),
    }
}
