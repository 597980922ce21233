//! The rasterizer's band stage, rasterization fused with resolve: each band of `BAND_PX`
//! pixel rows is rasterized into a small visibility buffer (nearest depth and triangle per
//! sample) and resolved right away, so the full-resolution sample buffer never exists.
//! Resolve shades every sample (`ssaa`) or each triangle once per pixel at the centroid of
//! the samples it covers, weighted by its coverage (`msaa`), and takes the passes from the
//! pixel's nearest triangle.

use super::options::{AntiAliasing, Passes, RasterOptions, RenderOutput};
use super::rasterize::fill_rows;
use super::shader::{Shader, Surf};
use cgnodes_api::prelude::*;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

/// Pixel rows per band.
pub(super) const BAND_PX: usize = 8;

/// Pixel columns per block: a band is resolved block by block.
const BLOCK_PX: usize = 16;

/// One RGBA pixel of a pass.
type Px = [f32; 4];

/// A band's slice of each of the six passes (colour, depth, normal, position, uv, base
/// colour), `None` for the passes not produced.
type BandOut<'a> = [Option<&'a mut [Px]>; 6];

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
    let passes = opts.passes;
    let mut buffers = PassBuffers::new(passes, w as usize * h as usize);
    let shaded = AtomicU64::new(0);
    if passes.color || passes.any_surface() {
        let resolver = BandResolver::new(sh, bins, cam, s, opts);
        let nbands = bins.len();
        let bands = buffers.bands(w as usize * BAND_PX, nbands);
        let bands_done = AtomicUsize::new(0);
        bands.into_par_iter().enumerate().for_each_init(
            BandScratch::new,
            |scratch, (bi, mut out)| {
                let count = resolver.band(scratch, bi, &mut out);
                shaded.fetch_add(count, Ordering::Relaxed);
                let k = bands_done.fetch_add(1, Ordering::Relaxed) + 1;
                (sh.progress)(k as f64 / nbands as f64);
            },
        );
    }
    buffers.into_output(w, h, triangles, shaded.into_inner())
}

/// The six full-resolution pass images being filled; only the passes asked for get a
/// buffer (the others stay empty and come out as 0x0 images).
struct PassBuffers([Vec<Px>; 6]);

impl PassBuffers {
    /// Zeroed buffers of `npx` pixels for the passes on in `passes`; the system allocates
    /// them lazily, and the bands write every colour pixel (the background where nothing
    /// is hit), in parallel.
    fn new(passes: Passes, npx: usize) -> Self {
        let alloc = |on: bool| {
            if on {
                vec![[0.0f32; 4]; npx]
            } else {
                Vec::new()
            }
        };
        PassBuffers([
            alloc(passes.color),
            alloc(passes.depth),
            alloc(passes.normal),
            alloc(passes.position),
            alloc(passes.uv),
            alloc(passes.base_color),
        ])
    }

    /// The buffers cut into `nbands` bands of `band_len` pixels, each band holding its
    /// slice of every produced pass, so the bands can be resolved in parallel.
    fn bands(&mut self, band_len: usize, nbands: usize) -> Vec<BandOut<'_>> {
        let mut chunks: Vec<std::vec::IntoIter<Option<&mut [Px]>>> = self
            .0
            .iter_mut()
            .map(|buf| {
                let v: Vec<Option<&mut [Px]>> = if buf.is_empty() {
                    (0..nbands).map(|_| None).collect()
                } else {
                    buf.chunks_mut(band_len).map(Some).collect()
                };
                v.into_iter()
            })
            .collect();
        (0..nbands)
            .map(|_| std::array::from_fn(|k| chunks[k].next().flatten()))
            .collect()
    }

    /// The filled buffers as the render's output images (`w x h`, or 0x0 when not
    /// produced), with the triangle and shading counts.
    fn into_output(self, w: u32, h: u32, triangles: usize, shaded: u64) -> RenderOutput {
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
        let [color, depth, normal, position, uv, base_color] = self.0;
        RenderOutput {
            color: img(color),
            depth: img(depth),
            normal: img(normal),
            position: img(position),
            uv: img(uv),
            base_color: img(base_color),
            triangles,
            shaded,
        }
    }
}

/// The samples of one triangle inside a pixel: what MSAA shades once at their centroid.
struct Group {
    /// The triangle.
    id: u32,
    /// Samples it covers.
    n: u32,
    /// Sum of the samples' x.
    sx: f64,
    /// Sum of the samples' y.
    sy: f64,
    /// Nearest depth among them.
    depth: f32,
}

/// One worker's reusable buffers: the band's visibility buffer (depth and triangle per
/// sample) and the current pixel's triangle groups.
struct BandScratch {
    zbuf: Vec<f32>,
    ibuf: Vec<u32>,
    groups: Vec<Group>,
}

impl BandScratch {
    /// Empty buffers; the groups start with room for a pixel's usual few triangles.
    fn new() -> Self {
        BandScratch {
            zbuf: Vec::new(),
            ibuf: Vec::new(),
            groups: Vec::with_capacity(16),
        }
    }
}

/// Where a pixel sits: its column and row in the image, and the index of its first sample
/// in the band's visibility buffer.
#[derive(Clone, Copy)]
struct PixelAt {
    px: usize,
    py: usize,
    k0: usize,
}

/// A pixel's running resolve: the sum of its shaded colours, its samples that hit nothing
/// and the shading evaluations spent on it.
struct PixelSum {
    acc: [f64; 3],
    empty: u32,
    count: u64,
}

/// What every band reads, fixed for the render: the shader, the sample grid and the
/// anti-aliasing mode.
struct BandResolver<'a> {
    sh: &'a Shader<'a>,
    bins: &'a [Vec<u32>],
    cam: &'a Camera,
    opts: &'a RasterOptions,
    /// Samples per pixel axis.
    s: u32,
    /// Sample columns and rows of the image.
    ws: u32,
    hs: u32,
    /// Sample rows per band.
    band_rows: u32,
    /// Samples per band.
    band_samples: usize,
    /// Pixel columns of the image.
    wu: usize,
    /// Samples per pixel, the colour's divisor.
    n_samples: f64,
    /// The background colour of a pixel nothing covers.
    bg: Px,
    /// Shade every sample (supersampling) or each triangle once per pixel (multisampling).
    ssaa: bool,
    msaa: bool,
    /// Whether any pass besides colour is produced.
    surface_passes: bool,
}

impl<'a> BandResolver<'a> {
    /// The resolver for `cam` at `s x s` samples per pixel with `opts`.
    fn new(
        sh: &'a Shader<'a>,
        bins: &'a [Vec<u32>],
        cam: &'a Camera,
        s: u32,
        opts: &'a RasterOptions,
    ) -> Self {
        let (ws, hs) = (cam.width * s, cam.height * s);
        let band_rows = BAND_PX as u32 * s;
        let lit = opts.passes.color;
        BandResolver {
            sh,
            bins,
            cam,
            opts,
            s,
            ws,
            hs,
            band_rows,
            band_samples: ws as usize * band_rows as usize,
            wu: cam.width as usize,
            n_samples: (s * s) as f64,
            bg: [
                opts.background[0] as f32,
                opts.background[1] as f32,
                opts.background[2] as f32,
                1.0,
            ],
            ssaa: lit && opts.aa == AntiAliasing::Supersampling,
            msaa: lit && opts.aa == AntiAliasing::Multisampling,
            surface_passes: opts.passes.any_surface(),
        }
    }

    /// Rasterizes band `bi` into the scratch visibility buffer and resolves its pixels into
    /// `out`; returns the shading evaluations spent.
    fn band(&self, scratch: &mut BandScratch, bi: usize, out: &mut BandOut) -> u64 {
        let s = self.s;
        scratch.zbuf.clear();
        scratch.zbuf.resize(self.band_samples, f32::INFINITY);
        scratch.ibuf.clear();
        scratch.ibuf.resize(self.band_samples, u32::MAX);
        let y_start = bi as u32 * self.band_rows;
        let y_end = (y_start + self.band_rows).min(self.hs);
        fill_rows(
            self.sh.setups,
            &self.bins[bi],
            y_start,
            y_end,
            self.ws,
            self.cam.near,
            self.cam.far,
            &mut scratch.zbuf,
            Some(&mut scratch.ibuf),
        );
        let mut count = 0u64;
        let rows = (y_end - y_start) as usize / s as usize;
        let (sz, wsu, wu) = (s as usize, self.ws as usize, self.wu);
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
                let at = PixelAt {
                    px,
                    py,
                    k0: row0 + px * sz,
                };
                count += self.pixel(at, r * wu + px, scratch, out);
            }
        }
        count
    }

    /// Resolves one pixel into index `o` of the band's passes; returns the shading
    /// evaluations spent.
    #[inline]
    fn pixel(&self, at: PixelAt, o: usize, scratch: &mut BandScratch, out: &mut BandOut) -> u64 {
        scratch.groups.clear();
        let mut sum = PixelSum {
            acc: [0.0f64; 3],
            empty: 0,
            count: 0,
        };
        let first = scratch.ibuf[at.k0];
        if self.uniform(&scratch.ibuf, at.k0, first) {
            let g = self.uniform_group(&scratch.zbuf, at, first);
            scratch.groups.push(g);
        } else {
            self.gather_samples(at, scratch, &mut sum);
        }
        let groups = &scratch.groups;
        if groups.is_empty() {
            if let Some(c) = out[0].as_deref_mut() {
                c[o] = self.bg;
            }
            return sum.count;
        }
        let nearest = nearest_group(groups);
        let pass_surf = self.shade_groups(groups, nearest, &mut sum);
        if let Some(c) = out[0].as_deref_mut() {
            for (a, c) in sum.acc.iter_mut().zip(self.opts.background) {
                *a += c * sum.empty as f64;
            }
            let n = self.n_samples;
            c[o] = [
                (sum.acc[0] / n) as f32,
                (sum.acc[1] / n) as f32,
                (sum.acc[2] / n) as f32,
                1.0,
            ];
        }
        if let Some(sf) = pass_surf {
            write_surface_passes(&mut out[1..], o, &sf);
        }
        sum.count
    }

    /// Whether every sample of the pixel at `k0` is on triangle `first` (most pixels): the
    /// fast path, never taken under supersampling, which shades each sample.
    #[inline]
    fn uniform(&self, ibuf: &[u32], k0: usize, first: u32) -> bool {
        let (sz, wsu) = (self.s as usize, self.ws as usize);
        !self.ssaa
            && first != u32::MAX
            && (0..sz).all(|j| {
                let k = k0 + j * wsu;
                ibuf[k..k + sz].iter().all(|&id| id == first)
            })
    }

    /// The group of a pixel whose samples are all on triangle `id`. The sums run in the
    /// same order as in `gather_samples`, so the result is the same.
    #[inline]
    fn uniform_group(&self, zbuf: &[f32], at: PixelAt, id: u32) -> Group {
        let (sz, wsu) = (self.s as usize, self.ws as usize);
        let (mut gx, mut gy, mut gd) = (0.0f64, 0.0f64, f32::INFINITY);
        for j in 0..sz {
            let yc = (at.py * sz + j) as f64 + 0.5;
            let k = at.k0 + j * wsu;
            for (i, &d) in zbuf[k..k + sz].iter().enumerate() {
                gx += (at.px * sz + i) as f64 + 0.5;
                gy += yc;
                gd = gd.min(d);
            }
        }
        Group {
            id,
            n: (sz * sz) as u32,
            sx: gx,
            sy: gy,
            depth: gd,
        }
    }

    /// The general path: groups the pixel's samples by triangle, counts the empty ones and,
    /// under supersampling, shades and sums every covered sample.
    #[inline]
    fn gather_samples(&self, at: PixelAt, scratch: &mut BandScratch, sum: &mut PixelSum) {
        let (sz, wsu) = (self.s as usize, self.ws as usize);
        let BandScratch { zbuf, ibuf, groups } = scratch;
        for j in 0..sz {
            let sy = at.py * sz + j;
            for i in 0..sz {
                let sx = at.px * sz + i;
                let k = at.k0 + j * wsu + i;
                let id = ibuf[k];
                if id == u32::MAX {
                    sum.empty += 1;
                    continue;
                }
                let (xc, yc) = (sx as f64 + 0.5, sy as f64 + 0.5);
                if self.ssaa {
                    if let Some(sf) = self.sh.surface(id as usize, xc, yc, 1.0, true) {
                        sum.count += 1;
                        for (a, c) in sum.acc.iter_mut().zip(sf.color) {
                            *a += c;
                        }
                    }
                }
                let d = zbuf[k];
                match groups.iter_mut().find(|g| g.id == id) {
                    Some(g) => {
                        g.n += 1;
                        g.sx += xc;
                        g.sy += yc;
                        g.depth = g.depth.min(d);
                    }
                    None => groups.push(Group {
                        id,
                        n: 1,
                        sx: xc,
                        sy: yc,
                        depth: d,
                    }),
                }
            }
        }
    }

    /// Shades the groups at their centroids under multisampling (adding each colour
    /// weighted by its coverage to `sum`), and returns the surface of group `nearest` when
    /// surface passes are produced.
    #[inline]
    fn shade_groups(&self, groups: &[Group], nearest: usize, sum: &mut PixelSum) -> Option<Surf> {
        let step = self.s as f64;
        let mut pass_surf = None;
        for (gi, gr) in groups.iter().enumerate() {
            let (x, y) = (gr.sx / gr.n as f64, gr.sy / gr.n as f64);
            if self.msaa {
                if let Some(sf) = self.sh.surface(gr.id as usize, x, y, step, true) {
                    sum.count += 1;
                    for (a, c) in sum.acc.iter_mut().zip(sf.color) {
                        *a += c * gr.n as f64;
                    }
                    if gi == nearest && self.surface_passes {
                        pass_surf = Some(sf);
                    }
                }
            } else if gi == nearest && self.surface_passes {
                pass_surf = self.sh.surface(gr.id as usize, x, y, step, false);
            }
        }
        pass_surf
    }
}

/// The index of the nearest group of a pixel (first on ties): the triangle that gives the
/// pixel's surface passes.
#[inline]
fn nearest_group(groups: &[Group]) -> usize {
    let mut nearest = 0;
    for (gi, gr) in groups.iter().enumerate() {
        if gr.depth < groups[nearest].depth {
            nearest = gi;
        }
    }
    nearest
}

/// Writes surface `sf` into pixel `o` of the produced surface passes (depth, normal,
/// position, uv, base colour, in that order).
#[inline]
fn write_surface_passes(passes: &mut [Option<&mut [Px]>], o: usize, sf: &Surf) {
    let f3 = |v: [f64; 3]| [v[0] as f32, v[1] as f32, v[2] as f32, 1.0];
    let d = sf.depth as f32;
    let vals = [
        [d, d, d, 1.0],
        f3(sf.n),
        f3(sf.p),
        [sf.uv[0] as f32, sf.uv[1] as f32, 0.0, 1.0],
        f3(sf.base),
    ];
    for (band, v) in passes.iter_mut().zip(vals) {
        if let Some(b) = band.as_deref_mut() {
            b[o] = v;
        }
    }
}
