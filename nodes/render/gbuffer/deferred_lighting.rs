//! `deferred_lighting`: Blinn-Phong per pixel from a G-buffer (Deering et al., "The
//! Triangle Processor and Normal Vector Shader", SIGGRAPH 1988, for shading after
//! visibility), Framework3D's `render_deferred_lighting` with the course's `blinn_phong.fs`.
//!
//! Per surface pixel with world position `p`, normal `n`, base colour `c`, metallic `m`
//! and roughness `r`: `I = ka c + sum over lights of V (kd E c cos(alpha) + ks E
//! cos^k(theta))`, the rasterizer's own model (`raster/shading.rs`: `ks = 0.8 m`,
//! `kd = 1 - ks`, `k` from `r`), with `E` the light's irradiance at `p` and `V` the
//! percentage-closer shadow-map visibility (`raster/shadow.rs`) when the shadow maps of
//! `shadow_mapping` are connected. So on `render_raster`'s G-buffer at one sample per pixel
//! the result is `render_raster`'s colour, except for what a G-buffer does not carry:
//! emission, and the shadow bias, which uses the shading normal in place of the geometric one.
//! Pixels without a surface get the background colour.

use super::shadow_mapping::{map_from_image, scene_bounds};
use super::{check_size, is_surface, light_at, pass_camera, rgb1};
use crate::raster::shading::{blinn_phong, roughness_to_exponent, specular_weight};
use crate::raster::shadow::{ShadowMap, ShadowParams};
use cgnodes_api::prelude::*;
use cgnodes_api::types::vec3::{normalize_recip as normalize, sub};

/// The G-buffer passes deferred lighting reads (all of one size).
#[derive(Clone, Copy)]
pub struct GBuffer<'a> {
    /// World-space position (alpha 0 where nothing was hit).
    pub position: &'a Image,
    /// World-space shading normal.
    pub normal: &'a Image,
    /// Base colour.
    pub base_color: &'a Image,
    /// Metallic in R, roughness in G; `None` uses the uniform values of `Lighting`.
    pub metallic_roughness: Option<&'a Image>,
}

/// The lighting settings.
#[derive(Clone, Debug)]
pub struct Lighting {
    /// The ambient term `ka Ia` (times the base colour).
    pub ambient: f64,
    /// Metallic where no metallic-roughness pass is given.
    pub metallic: f64,
    /// Roughness where no metallic-roughness pass is given.
    pub roughness: f64,
    /// Colour where no surface is.
    pub background: [f64; 3],
    /// Shadow-map bias and filtering.
    pub shadow: ShadowParams,
}

impl Default for Lighting {
    fn default() -> Self {
        Lighting {
            ambient: 0.2,
            metallic: 0.0,
            roughness: 0.5,
            background: [0.05; 3],
            shadow: ShadowParams::default(),
        }
    }
}

/// Lights the G-buffer `gb` seen from `cam` by `lights`, each with its shadow map in
/// `shadows` (same order; missing or `None` entries are unshadowed). The passes must share
/// one size (the node checks it).
pub fn deferred_lighting(
    gb: GBuffer,
    cam: &Camera,
    lights: &[Light],
    shadows: &[Option<ShadowMap>],
    set: &Lighting,
) -> Image {
    let (w, h) = (gb.position.width, gb.position.height);
    let forward = cam.look_at::<f64>().forward;
    super::image_from_fn(w, h, |x, y| {
        let pp = gb.position.get(x, y);
        if !is_surface(pp) {
            return rgb1(set.background);
        }
        let p = [pp[0] as f64, pp[1] as f64, pp[2] as f64];
        let nn = gb.normal.get(x, y);
        let bb = gb.base_color.get(x, y);
        let base = [bb[0] as f64, bb[1] as f64, bb[2] as f64];
        let mut color = base.map(|b| set.ambient * b);
        let Some(n) = normalize([nn[0] as f64, nn[1] as f64, nn[2] as f64]) else {
            return rgb1(color);
        };
        let (metallic, roughness) = match gb.metallic_roughness {
            Some(mr) => {
                let v = mr.get(x, y);
                (v[0] as f64, v[1] as f64)
            }
            None => (set.metallic, set.roughness),
        };
        let (ks, k) = (specular_weight(metallic), roughness_to_exponent(roughness));
        let v = normalize(sub(cam.eye, p)).unwrap_or(forward.map(|c| -c));
        for (i, light) in lights.iter().enumerate() {
            let Some((l, e)) = light_at(light, p) else {
                continue;
            };
            let f = blinn_phong(n, l, v, base, ks, k);
            if f == [0.0; 3] {
                continue;
            }
            let vis = match shadows.get(i) {
                Some(Some(map)) => map.visibility(p, n, l, &set.shadow),
                _ => 1.0,
            };
            for c in 0..3 {
                color[c] += vis * e[c] * f[c];
            }
        }
        rgb1(color)
    })
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Blinn-Phong lighting of a G-buffer (Framework3D's render_deferred_lighting), with shadow maps from shadow_mapping.");
    b.add_input::<Scene>("scene")
        .doc("The lights (and the camera, when 'camera' is not connected).");
    b.add_input::<Camera>("camera")
        .optional()
        .doc("The camera the G-buffer was rendered with (the eye of the specular term).");
    b.add_input::<Image>("position")
        .doc("World-space position pass.");
    b.add_input::<Image>("normal")
        .doc("World-space normal pass.");
    b.add_input::<Image>("base_color")
        .doc("Base (diffuse) colour pass.");
    b.add_input::<Image>("metallic_roughness")
        .optional()
        .doc("Metallic in R, roughness in G; else the uniform values below.");
    b.add_input::<Vec<Image>>("shadows")
        .optional()
        .doc("Shadow maps from shadow_mapping of the same scene, one per light.");
    let d = Lighting::default();
    b.add_input::<f64>("metallic")
        .default(d.metallic)
        .range(0.0, 1.0)
        .doc("Metallic without a metallic_roughness pass (ks = 0.8 metallic).");
    b.add_input::<f64>("roughness")
        .default(d.roughness)
        .range(0.0, 1.0)
        .doc("Roughness without a metallic_roughness pass (sets the exponent).");
    b.add_input::<f64>("ambient")
        .default(d.ambient)
        .range(0.0, 10.0)
        .doc("Ambient term ka*Ia, times the base colour.");
    crate::raster::render_raster::declare_shadow_params(b);
    b.add_input::<Color>("background")
        .default(Color(d.background))
        .doc("Colour where no surface is.");
    b.add_output::<Image>("color").doc("Lit linear colour.");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let scene: Arc<Scene> = ctx.input("scene")?;
    let position: Arc<Image> = ctx.input("position")?;
    let normal: Arc<Image> = ctx.input("normal")?;
    let base: Arc<Image> = ctx.input("base_color")?;
    let mr: Option<Arc<Image>> = ctx.input_opt("metallic_roughness")?;
    let (w, h) = (position.width, position.height);
    check_size("position", &position, w, h)?;
    check_size("normal", &normal, w, h)?;
    check_size("base_color", &base, w, h)?;
    if let Some(m) = &mr {
        check_size("metallic_roughness", m, w, h)?;
    }
    let cam = pass_camera(ctx.input_opt("camera")?, Some(&scene), w, h)?;
    let mut set = Lighting {
        metallic: ctx.input("metallic")?,
        roughness: ctx.input("roughness")?,
        ambient: ctx.input("ambient")?,
        background: ctx.input::<Color>("background")?.0,
        ..Default::default()
    };
    set.shadow = crate::raster::render_raster::read_shadow_params(ctx)?;
    for (n, v) in [
        ("metallic", set.metallic),
        ("roughness", set.roughness),
        ("ambient", set.ambient),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(NodeError::invalid(n, "must be finite and not negative"));
        }
    }
    let maps: Option<Vec<Arc<Image>>> = ctx.input_opt("shadows")?;
    let mut shadows = Vec::new();
    if let Some(maps) = maps {
        if maps.len() != scene.lights.len() {
            return Err(NodeError::invalid(
                "shadows",
                format!(
                    "{} shadow maps for {} lights: connect shadow_mapping of the same scene",
                    maps.len(),
                    scene.lights.len()
                ),
            ));
        }
        let bounds =
            scene_bounds(&scene).map_err(|e| NodeError::invalid("scene", e.to_string()))?;
        for (i, (img, light)) in maps.iter().zip(&scene.lights).enumerate() {
            let m = map_from_image(img, light, bounds)
                .map_err(|e| NodeError::invalid("shadows", format!("map {i}: {e}")))?;
            shadows.push(m);
        }
    }
    let gb = GBuffer {
        position: &position,
        normal: &normal,
        base_color: &base,
        metallic_roughness: mr.as_deref(),
    };
    let img = deferred_lighting(gb, &cam, &scene.lights, &shadows, &set);
    ctx.set_output("color", img);
    Ok(())
}

/// Registers `deferred_lighting`.
pub fn register(r: &mut Registry) {
    r.add("deferred_lighting", declare, execute);
}
