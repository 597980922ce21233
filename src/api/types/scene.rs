//! What renderers draw: the camera (with the look-at and projection geometry shared by the
//! rasterizer and the tracers), lights, materials and the scene.

use super::{Image, Mesh};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Which image axis the field of view spans.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum FovAxis {
    /// The vertical axis.
    Vertical,
    /// Whichever of width and height is smaller (Mitsuba's `fov_axis = smaller`).
    Smaller,
}

/// A pinhole camera looking from `eye` at `target`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Camera position.
    pub eye: [f64; 3],
    /// Point looked at.
    pub target: [f64; 3],
    /// Up direction.
    pub up: [f64; 3],
    /// Field of view in degrees along `fov_axis`.
    pub fov_deg: f64,
    /// Axis the field of view spans.
    pub fov_axis: FovAxis,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Near clipping distance.
    pub near: f64,
    /// Far clipping distance.
    pub far: f64,
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            eye: [0.0, 0.0, 3.0],
            target: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            fov_deg: 45.0,
            fov_axis: FovAxis::Vertical,
            width: 512,
            height: 512,
            near: 0.01,
            far: 1000.0,
        }
    }
}

impl Camera {
    /// The vertical field of view in radians, whatever axis `fov_deg` was given on.
    pub fn vertical_fov(&self) -> f64 {
        let f = self.fov_deg.to_radians();
        match self.fov_axis {
            FovAxis::Vertical => f,
            FovAxis::Smaller if self.height <= self.width => f,
            FovAxis::Smaller => {
                let aspect = self.height as f64 / self.width as f64;
                2.0 * ((f * 0.5).tan() * aspect).atan()
            }
        }
    }

    /// `tan(fov_y / 2)`: the half-height of the image plane at unit distance.
    pub fn tan_half_fov(&self) -> f64 {
        (0.5 * self.vertical_fov()).tan()
    }

    /// The focal length in pixels (square pixels): a camera-space point `(x, y, z)` (x right,
    /// y up, z forward) lands at pixel `(w/2 + f x/z, h/2 - f y/z)`.
    pub fn focal_length_px(&self) -> f64 {
        0.5 * self.height as f64 / self.tan_half_fov()
    }

    /// The look-at basis computed in precision `T` (f64 for the rasterizer, f32 for the
    /// tracers), right-handed world: `forward` points from the eye to the target,
    /// `right = forward x up`, `up = right x forward` (the `gluLookAt` convention). The
    /// lengths before normalization are returned too, so that each renderer rejects
    /// degenerate cameras with its own tolerance.
    pub fn look_at<T: CameraFloat>(&self) -> LookAt<T> {
        let v = |a: [f64; 3]| a.map(T::from_f64);
        let (eye, target, up) = (v(self.eye), v(self.target), v(self.up));
        let f = sub3(target, eye);
        let forward_len = len3(f);
        let f = scale3(f, T::ONE / forward_len);
        let r = cross3(f, up);
        let right_len = len3(r);
        let r = scale3(r, T::ONE / right_len);
        LookAt {
            eye,
            right: r,
            up: cross3(r, f),
            forward: f,
            forward_len,
            right_len,
        }
    }

    /// The rasterizer's orthonormal frame `[right, up, forward]` (see `look_at`). Fails when
    /// eye = target or `up` is parallel to the view.
    pub fn frame(&self) -> Result<[[f64; 3]; 3], String> {
        let b = self.look_at::<f64>();
        let fl = b.forward_len;
        if fl.is_nan() || fl <= 1e-12 {
            return Err("eye and target coincide".into());
        }
        let rl = b.right_len;
        let up_len = len3(self.up);
        if rl.is_nan() || rl <= 1e-9 * up_len.max(1e-300) || !rl.is_finite() {
            return Err("up is parallel to the viewing direction (or zero)".into());
        }
        Ok([b.right, b.up, b.forward])
    }

    /// Checks that the camera describes a usable projection (frame, field of view,
    /// resolution in 1..=16384, clip range).
    pub fn check(&self) -> Result<(), String> {
        self.frame()?;
        if !(self.fov_deg > 0.0 && self.fov_deg < 180.0) {
            return Err(format!("fov {} must lie in (0, 180) degrees", self.fov_deg));
        }
        if self.width == 0 || self.height == 0 || self.width > 16384 || self.height > 16384 {
            return Err(format!(
                "resolution {}x{} must lie in 1..=16384",
                self.width, self.height
            ));
        }
        if !(self.near > 0.0 && self.far > self.near && self.far.is_finite()) {
            return Err(format!(
                "need 0 < near < far, got near {} far {}",
                self.near, self.far
            ));
        }
        Ok(())
    }
}

/// A float type the camera geometry is computed in: f64 (rasterizer) or f32 (tracers).
pub trait CameraFloat:
    Copy
    + PartialOrd
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::Div<Output = Self>
{
    /// Zero.
    const ZERO: Self;
    /// One.
    const ONE: Self;
    /// Rounds an f64 to this type.
    fn from_f64(x: f64) -> Self;
    /// Square root.
    fn sqrt(self) -> Self;
}

impl CameraFloat for f64 {
    const ZERO: f64 = 0.0;
    const ONE: f64 = 1.0;
    fn from_f64(x: f64) -> f64 {
        x
    }
    fn sqrt(self) -> f64 {
        f64::sqrt(self)
    }
}

impl CameraFloat for f32 {
    const ZERO: f32 = 0.0;
    const ONE: f32 = 1.0;
    fn from_f64(x: f64) -> f32 {
        x as f32
    }
    fn sqrt(self) -> f32 {
        f32::sqrt(self)
    }
}

/// A camera's look-at basis in precision `T` (`Camera::look_at`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LookAt<T> {
    /// The eye, rounded to `T`.
    pub eye: [T; 3],
    /// Unit right vector (`forward x up`, normalized).
    pub right: [T; 3],
    /// Unit up vector (`right x forward`).
    pub up: [T; 3],
    /// Unit viewing direction.
    pub forward: [T; 3],
    /// `|target - eye|` (0 when they coincide).
    pub forward_len: T,
    /// `|forward x up|` before normalization (about 0 when `up` is parallel to the view).
    pub right_len: T,
}

impl<T: CameraFloat> LookAt<T> {
    /// World point `p` in camera space `(x right, y up, z forward)`: the view transform.
    #[inline]
    pub fn to_view(&self, p: [T; 3]) -> [T; 3] {
        let d = sub3(p, self.eye);
        [dot3(d, self.right), dot3(d, self.up), dot3(d, self.forward)]
    }

    /// Ray generation: the unit direction through the image-plane point `(sx, sy)` at unit
    /// distance from the eye (x right, y up), `normalize(forward + sx right + sy up)` (left
    /// as is if it has zero length).
    #[inline]
    pub fn ray_dir(&self, sx: T, sy: T) -> [T; 3] {
        let d = self.ray_dirs(&[sx], &[sy]);
        [d[0][0], d[1][0], d[2][0]]
    }

    /// `ray_dir` for `N` points at once, in loops over arrays without branches that the
    /// compiler turns into SIMD (the path tracer makes eight camera rays together), axis by
    /// point: `d[axis][i]`, so a caller reads one point's direction from three scalar loads
    /// instead of a copy of 12 bytes that the processor cannot forward to the loads of its
    /// components.
    #[inline(always)]
    pub fn ray_dirs<const N: usize>(&self, sx: &[T; N], sy: &[T; N]) -> [[T; N]; 3] {
        let mut d = [[T::ZERO; N]; 3];
        for (k, dk) in d.iter_mut().enumerate() {
            for i in 0..N {
                dk[i] = (self.forward[k] + self.right[k] * sx[i]) + self.up[k] * sy[i];
            }
        }
        for i in 0..N {
            let l = (d[0][i] * d[0][i] + d[1][i] * d[1][i] + d[2][i] * d[2][i]).sqrt();
            // A zero-length (or NaN) direction is left as is: scaled by exactly 1.
            let s = if l > T::ZERO { T::ONE / l } else { T::ONE };
            for dk in d.iter_mut() {
                dk[i] = dk[i] * s;
            }
        }
        d
    }
}

#[inline(always)]
fn sub3<T: CameraFloat>(a: [T; 3], b: [T; 3]) -> [T; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline(always)]
fn scale3<T: CameraFloat>(a: [T; 3], s: T) -> [T; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}
#[inline(always)]
fn dot3<T: CameraFloat>(a: [T; 3], b: [T; 3]) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline(always)]
fn len3<T: CameraFloat>(a: [T; 3]) -> T {
    dot3(a, a).sqrt()
}
#[inline(always)]
fn cross3<T: CameraFloat>(a: [T; 3], b: [T; 3]) -> [T; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// A light source.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Light {
    /// A point light radiating `color * intensity` (W/sr per channel) in every direction.
    Point {
        position: [f64; 3],
        color: [f64; 3],
        intensity: f64,
    },
    /// A distant light travelling along `direction`, with irradiance `color * intensity`.
    Directional {
        direction: [f64; 3],
        color: [f64; 3],
        intensity: f64,
    },
    /// Light arriving from infinitely far away in every direction (the tracers' sky):
    /// radiance `color * intensity` times the equirectangular `image` when there is one,
    /// turned by `rotation_deg` about +y. The rasterizer ignores it.
    Environment {
        image: Option<Arc<super::Image>>,
        color: [f64; 3],
        intensity: f64,
        rotation_deg: f64,
    },
}

/// How a surface scatters light (used by the ray and path tracers; the rasterizer uses
/// the Blinn-Phong parameters of `Material`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum MaterialKind {
    /// Lambertian diffuse.
    Diffuse,
    /// Perfect mirror.
    Mirror,
    /// Smooth dielectric with index of refraction `ior`.
    Dielectric { ior: f64 },
    /// GGX microfacet conductor.
    Conductor { roughness: f64 },
}

/// A surface's appearance.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Name (used for MTL files).
    pub name: String,
    /// Scattering model.
    pub kind: MaterialKind,
    /// Linear base colour (diffuse albedo).
    pub base_color: [f64; 3],
    /// Base colour texture, sampled through the mesh's UVs (multiplies `base_color`).
    pub base_color_texture: Option<Arc<Image>>,
    /// Metallic, 0 to 1.
    pub metallic: f64,
    /// Roughness, 0 to 1.
    pub roughness: f64,
    /// Tangent-space normal map.
    pub normal_map: Option<Arc<Image>>,
    /// Emitted radiance (linear RGB).
    pub emission: [f64; 3],
    /// Whether the emission leaves both sides of the surface.
    pub two_sided_emission: bool,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: "default".into(),
            kind: MaterialKind::Diffuse,
            base_color: [0.8, 0.8, 0.8],
            base_color_texture: None,
            metallic: 0.0,
            roughness: 0.5,
            normal_map: None,
            emission: [0.0; 3],
            two_sided_emission: false,
        }
    }
}

/// A mesh placed in a scene with its material.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SceneObject {
    /// The geometry (world space).
    pub mesh: Arc<Mesh>,
    /// Its material; `None` uses the mesh's own material or the default.
    pub material: Option<Arc<Material>>,
}

/// What a renderer draws: objects, lights and a camera.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Scene {
    /// Meshes with materials.
    pub objects: Vec<SceneObject>,
    /// Light sources (emissive materials are lights too, for the path tracer).
    pub lights: Vec<Light>,
    /// The camera, if the scene has one.
    pub camera: Option<Camera>,
}

impl Scene {
    /// A scene holding just one mesh (the implicit Mesh to Scene conversion).
    pub fn from_mesh(mesh: Arc<Mesh>) -> Scene {
        Scene {
            objects: vec![SceneObject {
                mesh,
                material: None,
            }],
            ..Default::default()
        }
    }
}

impl crate::node::Choice for FovAxis {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("vertical", FovAxis::Vertical),
        ("smaller", FovAxis::Smaller),
    ];
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn look_at_agrees_across_precisions_and_rays_go_forward() {
        let cam = Camera {
            eye: [1.0, 2.0, 3.0],
            target: [0.0, 0.5, -1.0],
            ..Default::default()
        };
        let (a, b) = (cam.look_at::<f64>(), cam.look_at::<f32>());
        for (u, v) in [(a.right, b.right), (a.up, b.up), (a.forward, b.forward)] {
            for k in 0..3 {
                assert!((u[k] - v[k] as f64).abs() < 1e-6);
            }
        }
        let d = a.ray_dir(0.0, 0.0);
        assert!((0..3).all(|k| (d[k] - a.forward[k]).abs() < 1e-15));
        let v = a.to_view(cam.target);
        assert!(v[0].abs() < 1e-12 && v[1].abs() < 1e-12 && (v[2] - a.forward_len).abs() < 1e-12);
        assert!(cam.check().is_ok());
        let flat = Camera {
            up: [0.0, 0.0, -1.0],
            target: [0.0, 0.0, 0.0],
            eye: [0.0, 0.0, 3.0],
            ..Default::default()
        };
        assert!(flat.frame().is_err());
    }
}
