//! Where every path sample starts: its random stream, film position, camera ray and that
//! ray's first hit (`Starts`), shared by the one-path loop (`path_one`) and the lane loop
//! (`path_lanes`), below both.

use super::bvh::Hit;
use super::camera_grid::CameraGrid;
use super::lane_math::Lane;
use super::render_path::PathSettings;
use super::render_scene::{PinholeCamera, RenderScene};
use super::sampling::{Pcg32, V3};
use std::marker::PhantomData;

/// One pixel sample to trace: pixel column, row and sample index.
pub type Job = (u32, u32, u32);

/// A batch of pixel samples for a path loop (`path_lanes::trace`,
/// `path_one::radiance_samples`) to trace: the scene, camera and its grid, the settings and
/// the samples.
#[derive(Clone, Copy)]
pub struct Batch<'a> {
    /// The flattened scene.
    pub sc: &'a RenderScene,
    /// The camera.
    pub cam: &'a PinholeCamera,
    /// The camera rays' first hits, when built (`CameraGrid::build`).
    pub grid: Option<&'a CameraGrid>,
    /// Samples per pixel, depth, strategy, seed.
    pub s: &'a PathSettings,
    /// The pixel samples.
    pub jobs: &'a [Job],
}

/// A traced sample: its radiance and film position.
#[derive(Clone, Copy, Debug, Default)]
pub struct Sample {
    /// Radiance estimate (may be non-finite; the caller discards those).
    pub c: V3,
    /// Film position, pixels.
    pub fx: f32,
    /// Film position, pixels.
    pub fy: f32,
}

/// The start of one pixel sample's path: its index in the batch's jobs, its random stream
/// (after the film position's two numbers), film position, camera ray direction and that
/// ray's first hit.
pub(crate) struct CameraSample {
    pub job: usize,
    pub rng: Pcg32,
    pub fx: f32,
    pub fy: f32,
    pub dir: V3,
    pub hit: Option<Hit>,
}

/// Pixel samples started together.
const STARTS: usize = 8;

/// Where every path sample starts, for both path loops, so that they draw the same numbers
/// and trace the same camera rays: the random streams, film positions and camera ray
/// directions of eight pixel samples at a time, made in array loops that the compiler
/// turns into SIMD (the streams' hashing and first steps, the directions' normalisation;
/// docs/path_tracing.md has the timings), then handed out one by one with their camera
/// hits, in the batch's order (its `Iterator::next`).
pub(crate) struct Starts<'a, F> {
    b: Batch<'a>,
    rng: [Pcg32; STARTS],
    fx: [f32; STARTS],
    fy: [f32; STARTS],
    /// Camera ray directions, axis by start (`dir[axis][i]`).
    dir: [[f32; STARTS]; 3],
    pix: [(u32, u32); STARTS],
    /// The camera rays' first hits.
    hits: [Option<Hit>; STARTS],
    /// The lane type of `CameraGrid::intersect8`.
    lanes: PhantomData<F>,
    /// The first job made, the starts made, and those handed out.
    first: usize,
    made: usize,
    taken: usize,
}

impl<'a, F: Lane> Starts<'a, F> {
    /// The starts of `b`'s jobs (none made yet: the first `next` makes some).
    pub(crate) fn new(b: Batch<'a>) -> Starts<'a, F> {
        Starts {
            b,
            rng: std::array::from_fn(|_| Pcg32::new(0, 0)),
            fx: [0.0; STARTS],
            fy: [0.0; STARTS],
            dir: [[0.0; STARTS]; 3],
            pix: [(0, 0); STARTS],
            hits: [None; STARTS],
            lanes: PhantomData,
            first: 0,
            made: 0,
            taken: 0,
        }
    }

    /// Makes the starts of `jobs` (1 to 8): the pixel sample's stream (`Pcg32::for_sample`),
    /// its film position from the stream's first two numbers, and the camera ray's
    /// direction. Unused lanes repeat the first job.
    #[inline(always)]
    fn make(&mut self, jobs: &[Job]) {
        let (cam, seed) = (self.b.cam, self.b.s.seed);
        let job = |i: usize| jobs[if i < jobs.len() { i } else { 0 }];
        let pixel: [u64; STARTS] =
            std::array::from_fn(|i| job(i).1 as u64 * cam.width as u64 + job(i).0 as u64);
        let sample: [u64; STARTS] = std::array::from_fn(|i| job(i).2 as u64);
        let (rng, u) = Pcg32::for_samples_2d(&pixel, &sample, seed);
        self.rng = rng;
        self.pix = std::array::from_fn(|i| (job(i).0, job(i).1));
        self.fx = std::array::from_fn(|i| job(i).0 as f32 + u[0][i]);
        self.fy = std::array::from_fn(|i| job(i).1 as f32 + u[1][i]);
        self.dir = cam.ray_dirs(&self.fx, &self.fy);
        // The camera rays' first hits: through the grid, eight at once when they share a
        // pixel (`CameraGrid::intersect8`); without one, the BVH's walks two at a time
        // (`Bvh::intersect_pair`), so that each overlaps the other's waits.
        let (sc, n) = (self.b.sc, jobs.len());
        let dir = |i: usize| [self.dir[0][i], self.dir[1][i], self.dir[2][i]];
        let one_pixel = self.pix.iter().all(|&p| p == self.pix[0]);
        self.hits = match self.b.grid {
            Some(g) => one_pixel
                .then(|| g.intersect8::<F>(&sc.tris, self.pix[0], cam.eye, &self.dir, cam.far))
                .flatten()
                .unwrap_or_else(|| {
                    std::array::from_fn(|i| {
                        let hit = || g.intersect(&sc.tris, self.pix[i], cam.eye, dir(i), cam.far);
                        (i < n).then(hit).flatten()
                    })
                }),
            None => {
                let ray = |i: usize| (cam.eye, dir(i), cam.far);
                let mut h = [None; STARTS];
                for i in (0..n).step_by(2) {
                    if i + 1 < n {
                        (h[i], h[i + 1]) = sc.bvh.intersect_pair(ray(i), ray(i + 1));
                    } else {
                        h[i] = sc.intersect(cam.eye, dir(i), cam.far);
                    }
                }
                h
            }
        };
        self.made = jobs.len();
        self.taken = 0;
    }
}

impl<F: Lane> Iterator for Starts<'_, F> {
    type Item = CameraSample;

    /// The start of the batch's next job, making those of the next eight jobs when none is
    /// left; `None` once every job has started.
    #[inline(always)]
    fn next(&mut self) -> Option<CameraSample> {
        let b = self.b;
        if self.taken == self.made {
            let first = self.first + self.made;
            if first == b.jobs.len() {
                return None;
            }
            self.make(&b.jobs[first..b.jobs.len().min(first + STARTS)]);
            self.first = first;
        }
        let i = self.taken;
        self.taken += 1;
        let dir = [self.dir[0][i], self.dir[1][i], self.dir[2][i]];
        Some(CameraSample {
            job: self.first + i,
            rng: self.rng[i].clone(),
            fx: self.fx[i],
            fy: self.fy[i],
            dir,
            hit: self.hits[i],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_load::load_obj_scene;
    use cgnodes_api::types::Camera;
    use std::path::Path;
    use wide::f32x8;

    /// Every start's camera hit is the one-ray answer for its direction (the grid's
    /// `intersect` with a grid, the BVH's `intersect` without), bit for bit, whichever way
    /// `Starts` found it: eight at once through one pixel (16 spp with a grid), one by one
    /// (3 spp, so that a batch of eight spans pixels), or in pairs (no grid), with a last
    /// batch shorter than eight.
    #[test]
    fn start_hits_are_the_one_ray_hits() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/cornell/cornell_box.obj");
        let sc = RenderScene::new(&load_obj_scene(&p, false).unwrap()).unwrap();
        let cam = PinholeCamera::new(&Camera {
            eye: [0.0, 0.0, 3.9],
            target: [0.0; 3],
            width: 24,
            height: 20,
            fov_deg: 39.3,
            far: 100.0,
            ..Default::default()
        })
        .unwrap();
        let grid = CameraGrid::build(&sc.tris, &cam).expect("the box fits the budget");
        let mut hits = 0;
        for (spp, grid) in [(16, Some(&grid)), (3, Some(&grid)), (16, None), (3, None)] {
            let s = PathSettings {
                spp,
                seed: 5,
                ..Default::default()
            };
            // Every pixel's samples, less the last three: the last batch is short.
            let mut jobs: Vec<Job> = (0..cam.height)
                .flat_map(|y| (0..cam.width).flat_map(move |x| (0..spp).map(move |k| (x, y, k))))
                .collect();
            jobs.truncate(jobs.len() - 3);
            let b = Batch {
                sc: &sc,
                cam: &cam,
                grid,
                s: &s,
                jobs: &jobs,
            };
            let starts: Vec<CameraSample> = Starts::<f32x8>::new(b).collect();
            assert_eq!(starts.len(), jobs.len());
            for (j, cs) in starts.iter().enumerate() {
                assert_eq!(cs.job, j);
                let (x, y, _) = jobs[j];
                let want = match grid {
                    Some(g) => g.intersect(&sc.tris, (x, y), cam.eye, cs.dir, cam.far),
                    None => sc.intersect(cam.eye, cs.dir, cam.far),
                };
                assert_eq!(
                    cs.hit.map(Hit::bits),
                    want.map(Hit::bits),
                    "spp {spp}, job {j}"
                );
                hits += want.is_some() as usize;
            }
        }
        assert!(hits > 10_000, "{hits} hits");
    }
}
