//! The rasterizer's light stage: each light's direction and irradiance prepared once, and
//! its shadow map rendered (orthographic for directional lights, a cube for point lights).

use super::geometry::SceneGeometry;
use super::options::RasterOptions;
use super::shadow::{directional_shadow_map, point_shadow_map, ShadowMap};
use cgnodes_api::prelude::*;
use cgnodes_api::types::vec3::{dot, normalize_recip as normalize, sub};
use rayon::prelude::*;

/// A light with its shadow map.
pub(super) struct LightPrep {
    pub(super) light: Light,
    /// A directional light's unit direction towards it and irradiance, computed once.
    pub(super) dir: Option<([f64; 3], [f64; 3])>,
    pub(super) map: Option<ShadowMap>,
    /// A directional light's shadow-bias factor per triangle (`shadow::bias_factor` of the
    /// triangle's geometric normal, computed once per triangle instead of per lookup);
    /// empty for other lights, which compute it per lookup.
    pub(super) factors: Vec<f64>,
}

/// The lights of `scene` with their shadow maps (one light per task); shadow maps only when
/// the colour pass is `lit` and `opts.shadows` is on.
pub(super) fn prepare_lights(
    scene: &Scene,
    g: &SceneGeometry,
    opts: &RasterOptions,
    lit: bool,
) -> Vec<LightPrep> {
    let res = opts.shadow_resolution.clamp(16, 8192);
    let diag = dot(sub(g.bounds.1, g.bounds.0), sub(g.bounds.1, g.bounds.0)).sqrt();
    scene
        .lights
        .par_iter()
        .map(|l| LightPrep {
            light: l.clone(),
            dir: match l {
                Light::Directional { .. } => light_at(l, [0.0; 3]),
                Light::Point { .. } | Light::Environment { .. } => None,
            },
            map: (lit && opts.shadows && !g.pos.is_empty())
                .then(|| match l {
                    Light::Directional { direction, .. } => {
                        Some(directional_shadow_map(&g.pos, *direction, g.bounds, res))
                    }
                    Light::Point { position, .. } => Some(point_shadow_map(
                        &g.pos,
                        *position,
                        (res / 2).max(16),
                        (1e-5 * diag).max(1e-9),
                    )),
                    // The rasterizer does not draw environment light.
                    Light::Environment { .. } => None,
                })
                .flatten(),
            factors: Vec::new(),
        })
        .collect::<Vec<_>>()
}

/// Unit direction from `p` towards a point or directional light and the irradiance it
/// gives there (colour times intensity, over the squared distance for a point light), as
/// the rasterizer lights a surface; `None` for environment lights and degenerate ones.
pub fn light_at(light: &Light, p: [f64; 3]) -> Option<([f64; 3], [f64; 3])> {
    match light {
        Light::Directional {
            direction,
            color,
            intensity,
        } => normalize(*direction).map(|d| (d.map(|c| -c), color.map(|c| c * intensity))),
        Light::Point {
            position,
            color,
            intensity,
        } => {
            let d = sub(*position, p);
            let r2 = dot(d, d);
            normalize(d).map(|l| (l, color.map(|c| c * intensity / r2)))
        }
        Light::Environment { .. } => None,
    }
}
