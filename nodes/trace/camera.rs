//! The tracers' camera: a pinhole camera that makes rays (`PinholeCamera`), and its frame in
//! f64 for projecting the scene onto the film (`Frame`, `CameraGrid`'s input). Below both the
//! scene (`render_scene`) and the camera-ray grid (`camera_grid`).

use super::sampling::V3;
use cgnodes_api::types::{Camera, LookAt};

/// Why a camera cannot be used by the tracers.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CameraError {
    /// A NaN or infinite eye, target or up.
    #[error("camera eye/target/up must be finite")]
    NonFinite,
    /// A film size of 0 or over 16384 pixels.
    #[error("camera resolution {width}x{height} must be between 1 and 16384")]
    Resolution {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
    /// A vertical field of view outside (0, 180) degrees.
    #[error("camera fov {0} must be in (0, 180) degrees")]
    Fov(f64),
    /// The eye and target coincide.
    #[error("camera target equals eye")]
    TargetIsEye,
    /// The up vector is parallel to the viewing direction.
    #[error("camera up is parallel to the viewing direction")]
    UpParallel,
}

/// A pinhole camera (Mitsuba `perspective` without depth of field).
#[derive(Clone, Debug)]
pub struct PinholeCamera {
    /// Eye position.
    pub eye: V3,
    /// The look-at basis (ray generation).
    basis: LookAt<f32>,
    tan_x: f32,
    tan_y: f32,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Far clip.
    pub far: f32,
}

impl PinholeCamera {
    /// Builds the camera; +x of the image is `forward x up` (world +x on the right for a
    /// camera looking down -z with +y up, as in Mitsuba's `look_at`).
    pub fn new(c: &Camera) -> Result<PinholeCamera, CameraError> {
        let fin = |a: [f64; 3]| a.iter().all(|x| x.is_finite());
        if !fin(c.eye) || !fin(c.target) || !fin(c.up) {
            return Err(CameraError::NonFinite);
        }
        if c.width == 0 || c.height == 0 || c.width > 16384 || c.height > 16384 {
            return Err(CameraError::Resolution {
                width: c.width,
                height: c.height,
            });
        }
        if !(c.fov_deg > 0.0 && c.fov_deg < 180.0) {
            return Err(CameraError::Fov(c.fov_deg));
        }
        // The look-at basis in f32, with the tracers' own tolerances.
        let b = c.look_at::<f32>();
        if b.forward_len == 0.0 {
            return Err(CameraError::TargetIsEye);
        }
        if b.right_len < 1e-6 {
            return Err(CameraError::UpParallel);
        }
        let tan_y = c.tan_half_fov() as f32;
        let tan_x = tan_y * c.width as f32 / c.height as f32;
        Ok(PinholeCamera {
            eye: b.eye,
            basis: b,
            tan_x,
            tan_y,
            width: c.width,
            height: c.height,
            far: if c.far > 0.0 && c.far.is_finite() {
                c.far as f32
            } else {
                f32::INFINITY
            },
        })
    }

    /// The unit direction through film position (`x`, `y`) in pixels, (0, 0) at the top-left
    /// corner of the image.
    #[inline]
    pub fn ray_dir(&self, x: f32, y: f32) -> V3 {
        let d = self.ray_dirs(&[x], &[y]);
        [d[0][0], d[1][0], d[2][0]]
    }

    /// `ray_dir` for `N` film positions at once (SIMD where the compiler can), axis by
    /// position: `d[axis][i]`.
    #[inline(always)]
    pub fn ray_dirs<const N: usize>(&self, x: &[f32; N], y: &[f32; N]) -> [[f32; N]; 3] {
        let (w, h) = (self.width as f32, self.height as f32);
        let sx: [f32; N] = std::array::from_fn(|i| (2.0 * x[i] / w - 1.0) * self.tan_x);
        let sy: [f32; N] = std::array::from_fn(|i| (1.0 - 2.0 * y[i] / h) * self.tan_y);
        self.basis.ray_dirs(&sx, &sy)
    }

    /// The camera's frame in f64, for projecting the scene onto the film
    /// (`CameraGrid::build`).
    pub fn frame(&self) -> Frame {
        let d = |a: V3| a.map(|x| x as f64);
        Frame {
            eye: d(self.basis.eye),
            axes: [d(self.basis.right), d(self.basis.up), d(self.basis.forward)],
            focal: 0.5 * self.height as f64 / self.tan_y as f64,
            size: (self.width, self.height),
        }
    }
}

/// The camera frame in f64: the eye, right, up and forward axes, and the focal length in
/// pixels (a camera-space point `(x, y, z)` lands at `(w/2 + f x/z, h/2 - f y/z)`).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// Eye.
    pub eye: [f64; 3],
    /// Right, up, forward (unit, camera space x, y, z).
    pub axes: [[f64; 3]; 3],
    /// Focal length in pixels.
    pub focal: f64,
    /// Film width and height in pixels.
    pub size: (u32, u32),
}

impl Frame {
    /// `p` in camera space.
    pub(crate) fn view(&self, p: V3) -> [f64; 3] {
        let d = [
            p[0] as f64 - self.eye[0],
            p[1] as f64 - self.eye[1],
            p[2] as f64 - self.eye[2],
        ];
        self.axes.map(|a| a[0] * d[0] + a[1] * d[1] + a[2] * d[2])
    }

    /// Film position of camera-space point `v` (`v[2] > 0`).
    pub(crate) fn film(&self, v: [f64; 3]) -> [f64; 2] {
        let (w, h) = (self.size.0 as f64, self.size.1 as f64);
        [
            0.5 * w + self.focal * v[0] / v[2],
            0.5 * h - self.focal * v[1] / v[2],
        ]
    }
}
