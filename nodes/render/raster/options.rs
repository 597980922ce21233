//! The rasterizer's settings (`RasterOptions`, `Passes`, `AntiAliasing`) and what it returns
//! (`RenderOutput`).

use super::shadow::ShadowParams;
use super::texture::Wrap;
use cgnodes_api::prelude::*;

/// Anti-aliasing mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AntiAliasing {
    /// Shade every sample.
    Supersampling,
    /// Shade each triangle once per pixel, weighted by its sample coverage.
    Multisampling,
}

/// Settings of `render`.
#[derive(Clone, Debug)]
pub struct RasterOptions {
    /// Samples per pixel along each axis (s; s^2 samples per pixel).
    pub samples_per_axis: u32,
    /// How samples are shaded.
    pub aa: AntiAliasing,
    /// Drop triangles facing away from the camera (clockwise on screen).
    pub cull_backfaces: bool,
    /// Render shadow maps.
    pub shadows: bool,
    /// Directional shadow map resolution (cube faces of point lights use half).
    pub shadow_resolution: u32,
    /// Shadow bias and PCF settings.
    pub shadow: ShadowParams,
    /// The ambient term `ka Ia` (multiplies the base colour).
    pub ambient: f64,
    /// Texture wrap mode.
    pub wrap: Wrap,
    /// Use mipmaps (trilinear filtering); otherwise bilinear on the full texture.
    pub mipmaps: bool,
    /// Colour where nothing is hit.
    pub background: [f64; 3],
    /// The images to produce (default all).
    pub passes: Passes,
}

/// Which images `render` produces. A pass left out comes back as an empty (0 x 0) image
/// and costs neither memory nor time; without `color` nothing is lit (no shadow maps).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Passes {
    /// Shaded colour.
    pub color: bool,
    /// View depth.
    pub depth: bool,
    /// World-space normal.
    pub normal: bool,
    /// World-space position.
    pub position: bool,
    /// Texture coordinates.
    pub uv: bool,
    /// Base colour.
    pub base_color: bool,
}

impl Passes {
    /// Every pass.
    pub const ALL: Passes = Passes {
        color: true,
        depth: true,
        normal: true,
        position: true,
        uv: true,
        base_color: true,
    };
    /// The shaded colour only.
    pub const COLOR: Passes = Passes {
        color: true,
        depth: false,
        normal: false,
        position: false,
        uv: false,
        base_color: false,
    };
    /// No pass (a base for struct update: `Passes { depth: true, ..Passes::NONE }`).
    pub const NONE: Passes = Passes {
        color: false,
        depth: false,
        normal: false,
        position: false,
        uv: false,
        base_color: false,
    };
    /// Whether any pass other than colour is on.
    pub(super) fn any_surface(&self) -> bool {
        self.depth || self.normal || self.position || self.uv || self.base_color
    }
}

impl Default for Passes {
    fn default() -> Self {
        Passes::ALL
    }
}

impl Default for RasterOptions {
    fn default() -> Self {
        RasterOptions {
            samples_per_axis: 2,
            aa: AntiAliasing::Multisampling,
            cull_backfaces: false,
            shadows: true,
            shadow_resolution: 2048,
            shadow: ShadowParams::default(),
            ambient: 0.2,
            wrap: Wrap::Repeat,
            mipmaps: true,
            background: [0.05, 0.05, 0.05],
            passes: Passes::ALL,
        }
    }
}

/// The rendered image and passes, with counts for benchmarks. Passes not asked for in
/// `RasterOptions::passes` are empty (0 x 0) images.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// Shaded linear colour.
    pub color: Image,
    /// View-space depth (distance along the viewing direction) in RGB.
    pub depth: Image,
    /// World-space shading normal (after normal mapping).
    pub normal: Image,
    /// World-space position.
    pub position: Image,
    /// Texture coordinates in R and G.
    pub uv: Image,
    /// Base colour (texture times factor).
    pub base_color: Image,
    /// Triangles rasterized (after culling and clipping).
    pub triangles: usize,
    /// Shading evaluations (lit surface points).
    pub shaded: u64,
}
