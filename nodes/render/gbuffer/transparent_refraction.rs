//! `transparent_refraction`: screen-space refraction of a transparent surface, Framework3D's
//! `render_transparent_refraction` with the course's `transparent_refraction.fs`.
//!
//! Per surface pixel at `p` with normal `n` (turned to face the eye), `I` the unit vector
//! to the eye: the view ray `-I` is refracted into the surface by Snell's law with relative
//! index `1 / ior` (GLSL `refract`) and reflected about `n` (`reflect`); both look up the
//! environment (the scene's first environment light, the tracers' equirectangular mapping,
//! or the `background` colour without one), mixed by Schlick's Fresnel approximation
//! (Schlick, "An Inexpensive BRDF Model for Physically-based Rendering", 1994):
//! `F = r0 + (1 - r0)(1 - cos)^5`, `r0 = ((1 - ior) / (1 + ior))^2`, `cos = I.n`;
//! `colour = (1 - F) T env(refracted) + F env(reflected)`, with `T` the base colour when
//! `tint` is on (else 1, as the course's shader); total internal reflection gives `F = 1`.
//! The course's shader refracts once, as if the object filled the space behind its front
//! surface (`exit = false`). With `exit` on (the default) the ray also leaves the object
//! through its back, modelled by the osculating sphere of the front surface: the curvature
//! `kappa = dn.dP / |dP|^2` is taken from the normal and position passes towards the
//! neighbour nearer in depth on each axis (averaged), the ray travels inside the sphere of
//! radius `1 / kappa` centred at `p - n / kappa` to its far side and refracts out with index
//! `ior` (for a sphere this is exact, and a glass ball turns the environment behind it over
//! in its centre, as a ball lens does); where the front is flat or concave (`kappa <= 0`)
//! the back is taken parallel to it, a slab, and the ray leaves in its original direction.
//! Only the entry's Fresnel term is applied. The point and directional lights add Blinn-Phong highlights
//! `highlight * E (n.h)^shininess` (no shadows). Pixels without a surface are black, as the
//! course's cleared target (an `environment_pass` after this fills them).

use super::{check_size, depth_hit, is_surface, light_at, pass_camera, rgb1, Sky};
use cgnodes_api::prelude::*;
use cgnodes_api::types::vec3::{add, dot, normalize_recip as normalize, sub};

/// Refraction settings.
#[derive(Clone, Debug)]
pub struct Refraction {
    /// Index of refraction of the surface (outside is 1).
    pub ior: f64,
    /// Weight of the lights' specular highlights.
    pub highlight: f64,
    /// Blinn-Phong exponent of the highlights.
    pub shininess: f64,
    /// Multiply the refracted light by the base colour.
    pub tint: bool,
    /// Refract out of the back as well (osculating sphere, see the module doc).
    pub exit: bool,
}

impl Default for Refraction {
    fn default() -> Self {
        Refraction {
            ior: 1.5,
            highlight: 1.0,
            shininess: 200.0,
            tint: false,
            exit: true,
        }
    }
}

/// Schlick's reflectance for cosine `c` and index `ior` (the course's `reflectance`).
pub fn schlick(c: f64, ior: f64) -> f64 {
    let r0 = ((1.0 - ior) / (1.0 + ior)).powi(2);
    r0 + (1.0 - r0) * (1.0 - c.clamp(0.0, 1.0)).powi(5)
}

/// GLSL `refract(i, n, eta)` for unit `i` (incident, towards the surface) and `n` (facing
/// against `i`); `None` on total internal reflection.
pub fn refract(i: [f64; 3], n: [f64; 3], eta: f64) -> Option<[f64; 3]> {
    let d = dot(n, i);
    let k = 1.0 - eta * eta * (1.0 - d * d);
    if k < 0.0 {
        return None;
    }
    let s = eta * d + k.sqrt();
    Some(std::array::from_fn(|c| eta * i[c] - s * n[c]))
}

/// GLSL `reflect(i, n)`.
pub fn reflect(i: [f64; 3], n: [f64; 3]) -> [f64; 3] {
    let d = 2.0 * dot(n, i);
    std::array::from_fn(|c| i[c] - d * n[c])
}

fn px3(p: [f32; 4]) -> [f64; 3] {
    [p[0] as f64, p[1] as f64, p[2] as f64]
}

/// The front surface's curvature at pixel `(x, y)`, `dn.dP / |dP|^2` towards the neighbour
/// nearer in depth on each axis, averaged over the axes that have one (0 without any).
fn curvature(position: &Image, normal: &Image, x: u32, y: u32, p: [f64; 3], n: [f64; 3]) -> f64 {
    let (w, h) = (position.width, position.height);
    let at = |qx: u32, qy: u32| {
        let (pp, nn) = (position.get(qx, qy), normal.get(qx, qy));
        if !is_surface(pp) {
            return None;
        }
        let dp = sub(px3(pp), p);
        let d2 = dot(dp, dp);
        let m = normalize(px3(nn))?;
        (d2 > 0.0).then(|| (d2, dot(sub(m, n), dp) / d2))
    };
    let axis = |a: Option<(u32, u32)>, b: Option<(u32, u32)>| {
        let a = a.and_then(|(qx, qy)| at(qx, qy));
        let b = b.and_then(|(qx, qy)| at(qx, qy));
        match (a, b) {
            (Some(u), Some(v)) => Some(if u.0 <= v.0 { u.1 } else { v.1 }),
            (u, v) => u.or(v).map(|t| t.1),
        }
    };
    let ks: Vec<f64> = [
        axis(
            (x + 1 < w).then_some((x + 1, y)),
            x.checked_sub(1).map(|xm| (xm, y)),
        ),
        axis(
            (y + 1 < h).then_some((x, y + 1)),
            y.checked_sub(1).map(|ym| (x, ym)),
        ),
    ]
    .into_iter()
    .flatten()
    .collect();
    if ks.is_empty() {
        0.0
    } else {
        ks.iter().sum::<f64>() / ks.len() as f64
    }
}

/// The direction in which a ray refracted into the surface at `p` (normal `n`, facing the
/// eye) along `t` leaves the object's back (see the module doc); `None` on total internal
/// reflection there.
fn exit_direction(
    p: [f64; 3],
    n: [f64; 3],
    t: [f64; 3],
    view: [f64; 3],
    kappa: f64,
    ior: f64,
) -> Option<[f64; 3]> {
    if !(kappa > 1e-9 && kappa.is_finite()) {
        return Some(view);
    }
    let r = 1.0 / kappa;
    let c: [f64; 3] = std::array::from_fn(|k| p[k] - r * n[k]);
    // P lies on the sphere: the far intersection is at s = -2 t.(P - C).
    let s = -2.0 * dot(t, sub(p, c));
    let p2: [f64; 3] = std::array::from_fn(|k| p[k] + s * t[k]);
    let n2 = normalize(sub(p2, c))?;
    refract(t, n2.map(|v| -v), ior)
}

/// Shades the surface pixels of the G-buffer (`position`, `normal`, `depth`, optional
/// `base_color`) seen from `eye` as a refracting surface (see the module doc).
#[allow(clippy::too_many_arguments)]
pub fn transparent_refraction(
    position: &Image,
    normal: &Image,
    depth: &Image,
    base_color: Option<&Image>,
    eye: [f64; 3],
    lights: &[Light],
    sky: &Sky,
    set: &Refraction,
) -> Image {
    let (w, h) = (position.width, position.height);
    super::image_from_fn(w, h, |x, y| {
        let pp = position.get(x, y);
        if !(depth_hit(depth.get(x, y)) && is_surface(pp)) {
            return [0.0, 0.0, 0.0, 1.0];
        }
        let p = [pp[0] as f64, pp[1] as f64, pp[2] as f64];
        let nn = normal.get(x, y);
        let (Some(mut n), Some(iv)) = (
            normalize([nn[0] as f64, nn[1] as f64, nn[2] as f64]),
            normalize(sub(eye, p)),
        ) else {
            return [0.0, 0.0, 0.0, 1.0];
        };
        if dot(n, iv) < 0.0 {
            n = n.map(|c| -c);
        }
        let view = iv.map(|c| -c);
        let refl = sky.eval(reflect(view, n));
        let inside = refract(view, n, 1.0 / set.ior);
        let out = match (inside, set.exit) {
            (Some(t), true) => {
                let kappa = curvature(position, normal, x, y, p, n);
                exit_direction(p, n, t, view, kappa, set.ior)
            }
            (t, _) => t,
        };
        let (fr, trans) = match (inside, out) {
            (Some(_), Some(t)) => (schlick(dot(iv, n), set.ior), sky.eval(t)),
            _ => (1.0, [0.0; 3]),
        };
        let tint = match (set.tint, base_color) {
            (true, Some(b)) => {
                let c = b.get(x, y);
                [c[0] as f64, c[1] as f64, c[2] as f64]
            }
            _ => [1.0; 3],
        };
        let mut c: [f64; 3] =
            std::array::from_fn(|k| (1.0 - fr) * tint[k] * trans[k] + fr * refl[k]);
        if set.highlight > 0.0 {
            for light in lights {
                let Some((l, e)) = light_at(light, p) else {
                    continue;
                };
                if dot(n, l) <= 0.0 {
                    continue;
                }
                let Some(hv) = normalize(add(l, iv)) else {
                    continue;
                };
                let s = set.highlight * dot(n, hv).max(0.0).powf(set.shininess);
                for k in 0..3 {
                    c[k] += s * e[k];
                }
            }
        }
        rgb1(c)
    })
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Screen-space refraction of a transparent surface onto the environment, Fresnel-weighted with its reflection (Framework3D's render_transparent_refraction).");
    b.add_input::<Scene>("scene")
        .doc("Lights (highlights) and the environment light (refracted and reflected); its camera when 'camera' is not connected.");
    b.add_input::<Camera>("camera")
        .optional()
        .doc("The camera the G-buffer was rendered with.");
    b.add_input::<Image>("position")
        .doc("World-space position pass.");
    b.add_input::<Image>("normal")
        .doc("World-space normal pass.");
    b.add_input::<Image>("depth")
        .doc("Depth pass: 0 or alpha 0 where nothing was hit.");
    b.add_input::<Image>("base_color")
        .optional()
        .doc("Base colour pass, the transmission tint when 'tint' is on.");
    let d = Refraction::default();
    b.add_input::<f64>("ior")
        .default(d.ior)
        .range(1.0, 4.0)
        .doc("Index of refraction (the course's shader uses 1.5).");
    b.add_input::<f64>("highlight")
        .default(d.highlight)
        .range(0.0, 100.0)
        .doc("Weight of the lights' specular highlights (0: none).");
    b.add_input::<f64>("shininess")
        .default(d.shininess)
        .range(1.0, 1e4)
        .doc("Blinn-Phong exponent of the highlights.");
    b.add_input::<bool>("tint")
        .default(d.tint)
        .doc("Multiply the refracted light by the base colour.");
    b.add_input::<bool>("exit")
        .default(d.exit)
        .doc("Refract out of the object's back too (its osculating sphere); off: one refraction, as the course's shader.");
    b.add_input::<Color>("background")
        .default(Color([0.0, 0.0, 0.0]))
        .doc("What refracted and reflected rays see when the scene has no environment light.");
    b.add_output::<Image>("color")
        .doc("Refracted and reflected environment on surfaces, black elsewhere.");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let scene: Arc<Scene> = ctx.input("scene")?;
    let position: Arc<Image> = ctx.input("position")?;
    let normal: Arc<Image> = ctx.input("normal")?;
    let depth: Arc<Image> = ctx.input("depth")?;
    let base: Option<Arc<Image>> = ctx.input_opt("base_color")?;
    let (w, h) = (position.width, position.height);
    check_size("position", &position, w, h)?;
    check_size("normal", &normal, w, h)?;
    check_size("depth", &depth, w, h)?;
    if let Some(b) = &base {
        check_size("base_color", b, w, h)?;
    }
    let cam = pass_camera(ctx.input_opt("camera")?, Some(&scene), w, h)?;
    let set = Refraction {
        ior: ctx.input("ior")?,
        highlight: ctx.input("highlight")?,
        shininess: ctx.input("shininess")?,
        tint: ctx.input("tint")?,
        exit: ctx.input("exit")?,
    };
    if !(set.ior.is_finite() && set.ior >= 1.0) {
        return Err(NodeError::invalid("ior", "must be finite and at least 1"));
    }
    if !(set.highlight.is_finite() && set.highlight >= 0.0) {
        return Err(NodeError::invalid(
            "highlight",
            "must be finite and not negative",
        ));
    }
    if !(set.shininess.is_finite() && set.shininess >= 1.0) {
        return Err(NodeError::invalid(
            "shininess",
            "must be finite and at least 1",
        ));
    }
    let bg: Color = ctx.input("background")?;
    let sky = Sky::new(&scene.lights, bg.0);
    if !sky.has_environment() {
        ctx.log(
            "warning: the scene has no environment light; refracted rays see the background colour",
        );
    }
    let img = transparent_refraction(
        &position,
        &normal,
        &depth,
        base.as_deref(),
        cam.eye,
        &scene.lights,
        &sky,
        &set,
    );
    ctx.set_output("color", img);
    Ok(())
}

/// Registers `transparent_refraction`.
pub fn register(r: &mut Registry) {
    r.add("transparent_refraction", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snell_and_fresnel() {
        // 45 degrees into glass: sin(t) = sin(45)/1.5.
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let t = refract([s, -s, 0.0], [0.0, 1.0, 0.0], 1.0 / 1.5).unwrap();
        assert!((t[0] - s / 1.5).abs() < 1e-12 && t[1] < 0.0);
        assert!((dot(t, t) - 1.0).abs() < 1e-12);
        // ior 1 goes straight on; glass to air past the critical angle reflects totally.
        assert_eq!(
            refract([s, -s, 0.0], [0.0, 1.0, 0.0], 1.0).unwrap(),
            [s, -s, 0.0]
        );
        assert!(refract([s, -s, 0.0], [0.0, 1.0, 0.0], 1.5).is_none());
        assert_eq!(reflect([s, -s, 0.0], [0.0, 1.0, 0.0]), [s, s, 0.0]);
        assert!((schlick(1.0, 1.5) - 0.04).abs() < 1e-12);
        assert_eq!(schlick(0.0, 1.5), 1.0);
    }
}
