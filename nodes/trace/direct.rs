//! Direct lighting at a path vertex from the lights that are not triangles: the delta
//! lights (point, directional), reached only by shadow rays, and the environment, sampled
//! by luminance and weighted against BSDF sampling with the power heuristic (Veach &
//! Guibas 1995). Area emitters are handled in `render_path` itself.

use super::bsdf::Bsdf;
use super::render_scene::{RenderScene, SurfacePoint, SHADOW_END};
use super::sampling::{add, dot, length, max_comp, mul, power_heuristic, scale, sub, v3, V3};
use cgnodes_api::types::Light;

/// The surface a direct-lighting estimate is made at.
pub struct Vertex<'a> {
    /// The point.
    pub p: V3,
    /// Unit direction towards the viewer.
    pub wo: V3,
    /// Normals and albedo.
    pub sp: &'a SurfacePoint,
    /// The scattering model.
    pub bsdf: Bsdf,
}

impl Vertex<'_> {
    /// The start of a shadow ray towards `wi`, off the geometric surface on `wi`'s side.
    #[inline]
    fn origin(&self, sc: &RenderScene, wi: V3) -> V3 {
        let ng = self.sp.ng;
        let side = if dot(ng, wi) > 0.0 {
            ng
        } else {
            scale(ng, -1.0)
        };
        sc.offset(self.p, side)
    }

    #[inline]
    fn f(&self, wi: V3) -> V3 {
        let sp = self.sp;
        self.bsdf.eval(sp.albedo, sp.ng, sp.ns, self.wo, wi)
    }
}

/// A point or directional light as seen from `p`: the unit direction to it, its irradiance
/// at `p` before the cosine, and where a shadow ray ends (`None`: infinitely far). `None` for
/// an environment, which is sampled instead (`environment_nee`), and for a point light at `p`.
pub fn delta_incidence(light: &Light, p: V3) -> Option<(V3, V3, Option<V3>)> {
    match light {
        Light::Point {
            position,
            color,
            intensity,
        } => {
            let lp = v3(*position);
            let d = sub(lp, p);
            let r2 = dot(d, d);
            if r2 <= 0.0 {
                return None;
            }
            // inverse-square falloff of a point light's intensity
            let e = scale(v3(*color), *intensity as f32 / r2);
            Some((scale(d, 1.0 / r2.sqrt()), e, Some(lp)))
        }
        Light::Directional {
            direction,
            color,
            intensity,
        } => {
            let d = v3(*direction);
            let wi = scale(d, -1.0 / length(d));
            Some((wi, scale(v3(*color), *intensity as f32), None))
        }
        Light::Environment { .. } => None,
    }
}

/// Radiance reflected toward the viewer from the point and directional lights (f cos E,
/// unshadowed ones only).
pub fn delta_lights(sc: &RenderScene, v: &Vertex) -> V3 {
    let mut l = [0.0f32; 3];
    for light in &sc.lights {
        let Some((wi, e, target)) = delta_incidence(light, v.p) else {
            continue;
        };
        let f = v.f(wi);
        if max_comp(f) <= 0.0 {
            continue;
        }
        let o = v.origin(sc, wi);
        let blocked = match target {
            Some(lp) => sc.bvh.occluded(o, sub(lp, o), SHADOW_END),
            None => sc.bvh.occluded(o, wi, f32::INFINITY),
        };
        if !blocked {
            l = add(l, mul(f, e));
        }
    }
    l
}

/// One environment sample for next-event estimation: f cos Le / pdf, times the power
/// heuristic weight against BSDF sampling when `mis` (else 1). Zero without an environment.
pub fn environment_nee(sc: &RenderScene, v: &Vertex, u: [f32; 2], mis: bool) -> V3 {
    let Some(env) = &sc.env else {
        return [0.0; 3];
    };
    let Some(es) = env.sample(u) else {
        return [0.0; 3];
    };
    if es.pdf.is_nan() || es.pdf <= 0.0 || max_comp(es.le) <= 0.0 {
        return [0.0; 3];
    }
    let sp = v.sp;
    let (f, bsdf_pdf) = v.bsdf.eval_pdf(sp.albedo, sp.ng, sp.ns, v.wo, es.wi);
    if max_comp(f) <= 0.0 {
        return [0.0; 3];
    }
    if sc.bvh.occluded(v.origin(sc, es.wi), es.wi, f32::INFINITY) {
        return [0.0; 3];
    }
    let w = if mis {
        power_heuristic(es.pdf, bsdf_pdf)
    } else {
        1.0
    };
    scale(mul(f, es.le), w / es.pdf)
}
