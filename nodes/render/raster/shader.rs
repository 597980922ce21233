//! Per-sample shading of the rasterizer: reconstructs the surface of a triangle at a sample
//! position (perspective-correct barycentrics, trilinear textures with UV derivatives one
//! pixel over, normal mapping in the tangent frame) and lights it with Blinn-Phong times the
//! shadow-map visibility of each light.

use super::geometry::{normal_mapped, SceneGeometry};
use super::lights::{light_at, LightPrep};
use super::options::RasterOptions;
use super::rasterize::{barycentric, TriSetup};
use super::shading;
use super::shadow;
use super::texture::MipTexture;
use cgnodes_api::prelude::*;
use cgnodes_api::types::vec3::{dot, normalize_recip as normalize, sub};

/// A material ready for shading.
pub(super) struct MatPrep {
    pub(super) base: [f64; 3],
    pub(super) tex: Option<MipTexture>,
    pub(super) nmap: Option<MipTexture>,
    pub(super) ks: f64,
    pub(super) k: f64,
    pub(super) emission: [f64; 3],
}

/// A reconstructed surface point.
pub(super) struct Surf {
    pub(super) p: [f64; 3],
    pub(super) n: [f64; 3],
    pub(super) uv: [f64; 2],
    pub(super) base: [f64; 3],
    pub(super) depth: f64,
    pub(super) color: [f64; 3],
}

pub(super) fn interp3(b: [f64; 3], v: &[[f64; 3]; 3]) -> [f64; 3] {
    std::array::from_fn(|k| b[0] * v[0][k] + b[1] * v[1][k] + b[2] * v[2][k])
}
pub(super) fn interp2(b: [f64; 3], v: &[[f64; 2]; 3]) -> [f64; 2] {
    std::array::from_fn(|k| b[0] * v[0][k] + b[1] * v[1][k] + b[2] * v[2][k])
}

pub(super) struct Shader<'a> {
    pub(super) g: &'a SceneGeometry,
    pub(super) setups: &'a [Option<TriSetup>],
    /// Unit geometric normal of each rasterized triangle (`None` when degenerate).
    pub(super) ngs: &'a [Option<[f64; 3]>],
    pub(super) mats: Vec<MatPrep>,
    pub(super) lights: Vec<LightPrep>,
    pub(super) eye: [f64; 3],
    pub(super) forward: [f64; 3],
    pub(super) opts: &'a RasterOptions,
    /// Called with the fraction of bands resolved.
    pub(super) progress: &'a (dyn Fn(f64) + Sync),
}

impl Shader<'_> {
    /// The surface of triangle `t` seen at sample-space point `(x, y)`; texture
    /// derivatives are taken `step` samples over; `lit` evaluates the lighting.
    pub(super) fn surface(&self, t: usize, x: f64, y: f64, step: f64, lit: bool) -> Option<Surf> {
        let s = self.setups[t].as_ref()?;
        let b = barycentric(&s.inv, x, y)?;
        let g = self.g;
        let pos = &g.pos[t];
        let p = interp3(b, pos);
        let v = normalize(sub(self.eye, p)).unwrap_or(self.forward.map(|c| -c));
        let mut ng = self.ngs[t]?;
        let flip = dot(ng, v) < 0.0;
        if flip {
            ng = ng.map(|c| -c);
        }
        let mut n = normalize(interp3(b, &g.nrm[t])).unwrap_or(ng);
        if flip {
            n = n.map(|c| -c);
        }
        let m = &self.mats[g.mat[t] as usize];
        let has_uv = g.has_uv[t];
        // Without UVs the corners' are zeros: skip reading them.
        let uv = if has_uv {
            interp2(b, &g.uv[t])
        } else {
            [0.0; 2]
        };
        let mut base = m.base;
        let (dx, dy) = if has_uv && (m.tex.is_some() || m.nmap.is_some()) {
            let d = |bb: Option<[f64; 3]>| {
                bb.map(|bb| {
                    let w = interp2(bb, &g.uv[t]);
                    [w[0] - uv[0], w[1] - uv[1]]
                })
                .unwrap_or([0.0; 2])
            };
            (
                d(barycentric(&s.inv, x + step, y)),
                d(barycentric(&s.inv, x, y + step)),
            )
        } else {
            ([0.0; 2], [0.0; 2])
        };
        if let (true, Some(tex)) = (has_uv, &m.tex) {
            let c = tex.trilinear(uv[0], uv[1], dx, dy, self.opts.wrap);
            base = [
                base[0] * c[0] as f64,
                base[1] * c[1] as f64,
                base[2] * c[2] as f64,
            ];
        }
        if let (true, Some(nm)) = (has_uv, &m.nmap) {
            let c = nm.trilinear(uv[0], uv[1], dx, dy, self.opts.wrap);
            if let Some(nn) = normal_mapped(n, &g.tan[t], b, c) {
                n = nn;
            }
        }
        let mut color = [0.0; 3];
        if lit {
            for k in 0..3 {
                color[k] = self.opts.ambient * base[k] + m.emission[k];
            }
            for lp in &self.lights {
                let (l, e) = match &lp.light {
                    Light::Directional { .. } => match lp.dir {
                        Some(le) => le,
                        None => continue,
                    },
                    Light::Point { .. } => match light_at(&lp.light, p) {
                        Some(le) => le,
                        None => continue,
                    },
                    Light::Environment { .. } => continue,
                };
                let f = shading::blinn_phong(n, l, v, base, m.ks, m.k);
                if f == [0.0; 3] {
                    continue;
                }
                let sp = &self.opts.shadow;
                let vis = match &lp.map {
                    Some(map) => {
                        let factor = match lp.factors.get(t) {
                            Some(&f) => f,
                            None => shadow::bias_factor(ng, l, sp),
                        };
                        map.visibility_with(p, factor, sp.pcf_radius)
                    }
                    None => 1.0,
                };
                for k in 0..3 {
                    color[k] += vis * e[k] * f[k];
                }
            }
        }
        Some(Surf {
            p,
            n,
            uv,
            base,
            depth: dot(sub(p, self.eye), self.forward),
            color,
        })
    }
}
