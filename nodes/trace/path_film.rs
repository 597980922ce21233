//! `render_path`'s film: the image cut into 16x16-pixel tiles rendered in parallel, each
//! pixel's samples traced (eight paths at a time by `path_lanes` where it applies, else one
//! at a time by `render_path::radiance`), splatted through the reconstruction filter, and
//! the per-pixel variance of the estimate. Tiles are summed in a fixed order, so images do
//! not depend on the thread count.

use super::bvh::TraceStacks;
use super::camera_grid::CameraGrid;
use super::camera_sample::{Batch, Job, Sample};
use super::path_lanes;
use super::path_one::radiance_samples;
use super::render_path::{Filter, PathSettings};
use super::render_scene::{PinholeCamera, RenderScene};
use cgnodes_api::types::Image;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Mitsuba's Gaussian filter: exp(-x^2 / (2 sigma^2)) minus its value at the radius,
/// sigma = 0.5 px, radius 2 px.
#[inline]
fn gaussian_1d(x: f32) -> f32 {
    const INV_2S2: f32 = 1.0 / (2.0 * 0.25);
    let edge = (-4.0 * INV_2S2).exp();
    ((-x * x * INV_2S2).exp() - edge).max(0.0)
}

const TILE: u32 = 16;
const MARGIN: i64 = 2;
/// Width of a tile's splat buffer (the tile grown by MARGIN on each side).
const PW: usize = (TILE as i64 + 2 * MARGIN) as usize;

struct TileOut {
    x0: u32,
    y0: u32,
    /// Splat sums (r, g, b, weight) over the tile grown by MARGIN on each side.
    splat: Vec<[f32; 4]>,
    /// Per own pixel: variance of the pixel mean.
    var: Vec<[f32; 3]>,
}

/// Renders `cam`'s view of `sc`. Returns the colour image (linear radiance) and, per
/// pixel, the variance of the pixel's estimate (sample variance of its own samples over
/// spp, before filtering). `progress` receives the fraction of tiles done. Scenes the
/// lane loop handles (`path_lanes::handles`: every material diffuse) are traced eight
/// paths at a time, with the same result bit for bit.
pub fn render(
    sc: &RenderScene,
    cam: &PinholeCamera,
    s: &PathSettings,
    progress: &(dyn Fn(f64) + Sync),
) -> (Image, Image) {
    render_opts(sc, cam, s, progress, Shortcuts::default())
}

/// The ways `render` may take to the same estimate; all are on by default, and switched
/// off to measure what each buys and to check that they change nothing.
#[derive(Clone, Copy, Debug)]
pub struct Shortcuts {
    /// Eight paths at a time on lanes where `path_lanes::handles` the scene (the image
    /// is the one-at-a-time loop's bit for bit).
    pub lanes: bool,
    /// Camera rays' first hits from per-pixel candidate lists (`CameraGrid`) instead of
    /// the BVH (the same hits but for ties between triangles at equal distance).
    pub camera_grid: bool,
    /// Camera rays per triangle from which the grid is built (default 6: with fewer,
    /// building it costs more than it saves).
    pub grid_rays_per_triangle: u64,
    /// Both loops' second builds for x86-64-v3 CPUs (AVX2 and companions), where the CPU
    /// has it (the same bits as the baseline build).
    pub x86_64_v3: bool,
}

impl Default for Shortcuts {
    fn default() -> Self {
        Shortcuts {
            lanes: true,
            camera_grid: true,
            grid_rays_per_triangle: 6,
            x86_64_v3: true,
        }
    }
}

/// `render` with a choice of `Shortcuts`.
pub fn render_opts(
    sc: &RenderScene,
    cam: &PinholeCamera,
    s: &PathSettings,
    progress: &(dyn Fn(f64) + Sync),
    opts: Shortcuts,
) -> (Image, Image) {
    let lanes = opts.lanes && path_lanes::handles(sc);
    let (w, h) = (cam.width, cam.height);
    // Building the grid costs more than it saves below about 5 camera rays per triangle
    // (igea, docs/path_tracing.md, "How it runs"): build it only when there are more.
    let rays = w as u64 * h as u64 * s.spp as u64;
    let enough = rays
        >= opts
            .grid_rays_per_triangle
            .saturating_mul(sc.tris.len() as u64);
    let grid = if opts.camera_grid && enough {
        CameraGrid::build(&sc.tris, cam)
    } else {
        None
    };
    let grid = grid.as_ref();
    let mut tiles = Vec::new();
    for y0 in (0..h).step_by(TILE as usize) {
        for x0 in (0..w).step_by(TILE as usize) {
            tiles.push((x0, y0));
        }
    }
    let done = AtomicUsize::new(0);
    let ntiles = tiles.len();
    // One tile per rayon job: rayon's adaptive split otherwise hands each thread a run of
    // tiles it never splits again unless stolen early, and on a scene whose halves cost the
    // same (the box) one thread idled 15-26 ms at the end of an 800 ms render.
    let outs: Vec<TileOut> = tiles
        .par_iter()
        .with_max_len(1)
        .map(|&(x0, y0)| {
            let out = render_tile(sc, cam, grid, s, (x0, y0), lanes, opts.x86_64_v3);
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress(d as f64 / ntiles as f64);
            out
        })
        .collect();
    gather(&outs, w, h)
}

/// Traces and splats the samples of the tile whose top-left pixel is `(x0, y0)`.
fn render_tile(
    sc: &RenderScene,
    cam: &PinholeCamera,
    grid: Option<&CameraGrid>,
    s: &PathSettings,
    (x0, y0): (u32, u32),
    lanes: bool,
    v3: bool,
) -> TileOut {
    let x1 = (x0 + TILE).min(cam.width);
    let y1 = (y0 + TILE).min(cam.height);
    let mut t = TileOut {
        x0,
        y0,
        splat: vec![[0.0f32; 4]; PW * PW],
        var: Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize),
    };
    // Pixels per batch of samples (about 16k samples, so lanes seldom wait for a batch's
    // last paths).
    let ppc = (16384 / s.spp as usize).max(1);
    let mut stacks = TraceStacks::new();
    let pixels: Vec<(u32, u32)> = (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| (x, y)))
        .collect();
    let spp = s.spp as usize;
    for chunk in pixels.chunks(ppc) {
        let jobs: Vec<Job> = chunk
            .iter()
            .flat_map(|&(x, y)| (0..s.spp).map(move |k| (x, y, k)))
            .collect();
        let b = Batch {
            sc,
            cam,
            grid,
            s,
            jobs: &jobs,
        };
        let samples = if lanes {
            path_lanes::trace(b, &mut stacks, v3)
        } else {
            radiance_samples(b, &mut stacks, v3)
        };
        for (j, &(x, y)) in chunk.iter().enumerate() {
            let v = t.add_pixel(cam, s.filter, (x, y), &samples[j * spp..(j + 1) * spp]);
            t.var.push(v);
        }
    }
    t
}

impl TileOut {
    /// Splats pixel `(x, y)`'s samples (non-finite ones as black) and returns the variance
    /// of the pixel's mean.
    fn add_pixel(
        &mut self,
        cam: &PinholeCamera,
        filter: Filter,
        (x, y): (u32, u32),
        own: &[Sample],
    ) -> [f32; 3] {
        let (mut s1, mut s2) = ([0.0f64; 3], [0.0f64; 3]);
        for &Sample { c, fx, fy } in own {
            let c = if c.iter().all(|v| v.is_finite()) {
                c
            } else {
                [0.0; 3]
            };
            for j in 0..3 {
                s1[j] += c[j] as f64;
                s2[j] += (c[j] as f64) * (c[j] as f64);
            }
            match filter {
                Filter::Box => {
                    let i = (y - self.y0) as usize + MARGIN as usize;
                    let jx = (x - self.x0) as usize + MARGIN as usize;
                    let a = &mut self.splat[i * PW + jx];
                    a[0] += c[0];
                    a[1] += c[1];
                    a[2] += c[2];
                    a[3] += 1.0;
                }
                Filter::Gaussian => self.splat_gaussian(cam, c, fx, fy),
            }
        }
        let n = own.len() as f64;
        let mut v = [0.0f32; 3];
        if own.len() > 1 {
            for j in 0..3 {
                let m = s1[j] / n;
                v[j] = (((s2[j] / n - m * m) * n / (n - 1.0)).max(0.0) / n) as f32;
            }
        }
        v
    }

    /// Adds radiance `c` sampled at film position (`fx`, `fy`) to the pixels whose
    /// centres lie within the Gaussian's radius, with their filter weights.
    fn splat_gaussian(&mut self, cam: &PinholeCamera, c: [f32; 3], fx: f32, fy: f32) {
        let (w, h) = (cam.width as i64, cam.height as i64);
        let cx0 = (fx - 0.5 - 2.0).ceil() as i64;
        let cy0 = (fy - 0.5 - 2.0).ceil() as i64;
        let mut wx = [0.0f32; 5];
        let mut wy = [0.0f32; 5];
        for k in 0..5 {
            wx[k] = gaussian_1d((cx0 + k as i64) as f32 + 0.5 - fx);
            wy[k] = gaussian_1d((cy0 + k as i64) as f32 + 0.5 - fy);
        }
        for (ky, wyk) in wy.iter().enumerate() {
            let py = cy0 + ky as i64;
            if *wyk <= 0.0 || py < 0 || py >= h {
                continue;
            }
            let i = (py - self.y0 as i64 + MARGIN) as usize;
            for (kx, wxk) in wx.iter().enumerate() {
                let px = cx0 + kx as i64;
                if *wxk <= 0.0 || px < 0 || px >= w {
                    continue;
                }
                let jx = (px - self.x0 as i64 + MARGIN) as usize;
                let wt = wxk * wyk;
                let a = &mut self.splat[i * PW + jx];
                a[0] += c[0] * wt;
                a[1] += c[1] * wt;
                a[2] += c[2] * wt;
                a[3] += wt;
            }
        }
    }
}

/// Sums the tiles' splats, normalises each pixel by its filter weight and places the
/// variances, image rows in parallel. Each pixel adds the tiles that cover it in tile
/// order, so the sums do not depend on the thread count.
fn gather(outs: &[TileOut], w: u32, h: u32) -> (Image, Image) {
    let wu = w as usize;
    let tiles_x = w.div_ceil(TILE) as usize;
    let mut color = Image::new(w, h, [0.0, 0.0, 0.0, 1.0]);
    let mut variance = Image::new(w, h, [0.0, 0.0, 0.0, 1.0]);
    let rows = color.pixels.par_chunks_mut(wu);
    let var_rows = variance.pixels.par_chunks_mut(wu);
    rows.zip(var_rows)
        .enumerate()
        .for_each(|(y, (row, var_row))| {
            let mut acc = vec![[0.0f64; 4]; wu];
            // The tile rows whose splats, grown by MARGIN, reach image row y (`outs` holds the
            // tiles row by row).
            let first = (y as i64 - MARGIN).max(0) as usize / TILE as usize;
            let last = (y + MARGIN as usize).min(h as usize - 1) / TILE as usize;
            for t in &outs[first * tiles_x..(last + 1) * tiles_x] {
                let i = y as i64 - (t.y0 as i64 - MARGIN);
                if !(0..PW as i64).contains(&i) {
                    continue;
                }
                let splat = &t.splat[i as usize * PW..(i as usize + 1) * PW];
                for (j, sv) in splat.iter().enumerate() {
                    let px = t.x0 as i64 - MARGIN + j as i64;
                    if px < 0 || px >= w as i64 {
                        continue;
                    }
                    let a = &mut acc[px as usize];
                    for k in 0..4 {
                        a[k] += sv[k] as f64;
                    }
                }
            }
            for (px, a) in row.iter_mut().zip(&acc) {
                if a[3] > 0.0 {
                    *px = [
                        (a[0] / a[3]) as f32,
                        (a[1] / a[3]) as f32,
                        (a[2] / a[3]) as f32,
                        1.0,
                    ];
                }
            }
            let own = y / TILE as usize;
            for t in &outs[own * tiles_x..(own + 1) * tiles_x] {
                let tw = ((t.x0 + TILE).min(w) - t.x0) as usize;
                let k0 = (y - t.y0 as usize) * tw;
                for (k, v) in t.var[k0..k0 + tw].iter().enumerate() {
                    var_row[t.x0 as usize + k] = [v[0], v[1], v[2], 1.0];
                }
            }
        });
    (color, variance)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Pcg32;

    /// The plain serial sum: every tile's splat added into one accumulator in tile order.
    fn gather_serial(outs: &[TileOut], w: u32, h: u32) -> (Image, Image) {
        let mut acc = vec![[0.0f64; 4]; (w * h) as usize];
        let mut variance = Image::new(w, h, [0.0, 0.0, 0.0, 1.0]);
        for t in outs {
            for i in 0..PW as i64 {
                for j in 0..PW as i64 {
                    let (py, px) = (t.y0 as i64 - MARGIN + i, t.x0 as i64 - MARGIN + j);
                    if (0..h as i64).contains(&py) && (0..w as i64).contains(&px) {
                        let a = &mut acc[(py * w as i64 + px) as usize];
                        let sv = t.splat[(i * PW as i64 + j) as usize];
                        for k in 0..4 {
                            a[k] += sv[k] as f64;
                        }
                    }
                }
            }
            let tw = (t.x0 + TILE).min(w) - t.x0;
            for (k, v) in t.var.iter().enumerate() {
                let (x, y) = (t.x0 + k as u32 % tw, t.y0 + k as u32 / tw);
                variance.set(x, y, [v[0], v[1], v[2], 1.0]);
            }
        }
        let mut color = Image::new(w, h, [0.0, 0.0, 0.0, 1.0]);
        for (px, a) in color.pixels.iter_mut().zip(&acc) {
            if a[3] > 0.0 {
                let c = [0, 1, 2].map(|k| (a[k] / a[3]) as f32);
                *px = [c[0], c[1], c[2], 1.0];
            }
        }
        (color, variance)
    }

    #[test]
    fn row_parallel_gather_is_the_serial_sum() {
        // Sizes that leave partial tiles on both axes, and one of a single tile row.
        for (w, h) in [(37u32, 21u32), (100, 70), (5, 3)] {
            let mut rng = Pcg32::new(w as u64, h as u64);
            let mut outs = Vec::new();
            for y0 in (0..h).step_by(TILE as usize) {
                for x0 in (0..w).step_by(TILE as usize) {
                    let own = ((x0 + TILE).min(w) - x0) * ((y0 + TILE).min(h) - y0);
                    // Values a sum of three or four of which rounds differently in
                    // another order (1 + 2^-53 + 2^-53 is 1 added left to right and
                    // 1 + 2^-52 right to left), so that a change of order shows.
                    let mut val = || {
                        let pick = [1.0, -1.0, 3.0, 2f32.powi(-53), 2f32.powi(-54)];
                        pick[rng.next_u32() as usize % pick.len()]
                    };
                    outs.push(TileOut {
                        x0,
                        y0,
                        splat: (0..PW * PW).map(|_| [val(), val(), val(), val()]).collect(),
                        var: (0..own).map(|_| [val(), val(), val()]).collect(),
                    });
                }
            }
            let (c, v) = gather(&outs, w, h);
            let (c_ref, v_ref) = gather_serial(&outs, w, h);
            let bits = |im: &Image| {
                im.pixels
                    .iter()
                    .flatten()
                    .map(|x| x.to_bits())
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(&c), bits(&c_ref), "colour {w}x{h}");
            assert_eq!(bits(&v), bits(&v_ref), "variance {w}x{h}");
        }
    }
}
