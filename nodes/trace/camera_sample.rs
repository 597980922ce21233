//! Where every path sample starts: its random stream, film position, camera ray and that
//! ray's first hit (`camera_sample`), shared by the one-path loop (`path_film`) and the
//! lane loop (`path_lanes`), below both.

use super::bvh::Hit;
use super::camera_grid::CameraGrid;
use super::render_path::PathSettings;
use super::render_scene::{PinholeCamera, RenderScene};
use super::sampling::{Pcg32, V3};

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

/// The start of one pixel sample's path: its random stream (after the film position's two
/// numbers), film position, camera ray direction and that ray's first hit.
pub(crate) struct CameraSample {
    pub rng: Pcg32,
    pub fx: f32,
    pub fy: f32,
    pub dir: V3,
    pub hit: Option<Hit>,
}

/// Starts sample `k` of pixel `(x, y)`: both path loops begin here, so they draw the same
/// numbers and trace the same camera ray (through `grid` when there is one).
#[inline(always)]
pub(crate) fn camera_sample(
    sc: &RenderScene,
    cam: &PinholeCamera,
    grid: Option<&CameraGrid>,
    seed: u64,
    (x, y, k): Job,
) -> CameraSample {
    let pix = y as u64 * cam.width as u64 + x as u64;
    let mut rng = Pcg32::for_sample(pix, k as u64, seed);
    let [ux, uy] = rng.next_2d();
    let (fx, fy) = (x as f32 + ux, y as f32 + uy);
    let dir = cam.ray_dir(fx, fy);
    let hit = match grid {
        Some(g) => g.intersect(&sc.tris, (x, y), cam.eye, dir, cam.far),
        None => sc.intersect(cam.eye, dir, cam.far),
    };
    CameraSample {
        rng,
        fx,
        fy,
        dir,
        hit,
    }
}
