//! The tracers' shading features (issue 28): smooth shading normals, textures and normal
//! maps, and the environment light, each against an analytic or independent reference.

use cgnodes::nodes::trace::render_path::{render_path, Filter, PathSettings, Strategy};
use cgnodes::nodes::trace::render_whitted::{render_whitted, WhittedSettings};
use cgnodes::types::{Camera, FovAxis, Image, Light, Material, Scene, SceneObject};
use std::sync::Arc;

use crate::trace::{mean, patch_mean, sphere};

fn noop(_: f64) {}

fn camera(eye: [f64; 3], fov: f64, w: u32, h: u32) -> Camera {
    Camera {
        eye,
        target: [0.0; 3],
        up: [0.0, 1.0, 0.0],
        fov_deg: fov,
        fov_axis: FovAxis::Smaller,
        width: w,
        height: h,
        near: 0.001,
        far: 100.0,
    }
}

fn lum(p: [f32; 4]) -> f64 {
    0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
}

/// A 24-segment diffuse sphere lit by a directional light from the camera.
fn lit_sphere() -> Scene {
    Scene {
        objects: vec![SceneObject {
            mesh: Arc::new(sphere([0.0; 3], 1.0, 12, false)),
            material: Some(Arc::new(Material {
                base_color: [0.8; 3],
                ..Default::default()
            })),
        }],
        lights: vec![Light::Directional {
            direction: [0.0, 0.0, -1.0],
            color: [1.0; 3],
            intensity: 3.0,
        }],
        camera: Some(camera([0.0, 0.0, 5.0], 30.0, 96, 96)),
    }
}

/// The largest |second difference| of luminance along the middle scanline over the central
/// 60% of the sphere's width (where the true shading is smooth), relative to the peak.
fn max_step(img: &Image) -> f64 {
    let y = img.height / 2;
    let l: Vec<f64> = (0..img.width).map(|x| lum(img.get(x, y))).collect();
    let peak = l.iter().cloned().fold(0.0, f64::max);
    // The sphere spans the pixels with light; take its middle.
    let lit: Vec<usize> = (0..l.len()).filter(|&i| l[i] > 0.05 * peak).collect();
    let (a, b) = (lit[0], *lit.last().unwrap());
    let (c, h) = ((a + b) / 2, (b - a) * 3 / 10);
    (c - h + 1..c + h)
        .map(|i| (l[i + 1] - 2.0 * l[i] + l[i - 1]).abs())
        .fold(0.0, f64::max)
        / peak
}

/// A sphere mesh with (computed) smooth normals renders without steps along a scanline:
/// its largest second difference is within the noise, while the flat-shaded render of the
/// same mesh (crease angle 0) has facet steps several times larger. Both tracers.
#[test]
fn smooth_normals_remove_the_facet_steps() {
    let scene = lit_sphere();
    let path = |crease: f64| {
        let s = PathSettings {
            spp: 16,
            max_depth: 2,
            filter: Filter::Box,
            crease_deg: crease,
            ..Default::default()
        };
        render_path(&scene, None, &s, &noop).unwrap()
    };
    let (smooth, var) = path(60.0);
    let (flat, _) = path(0.0);
    // Noise of a second difference: the sd of a pixel (its variance is in `var`) times
    // sqrt(6) (the 1, -2, 1 stencil), relative to the peak, as 4 sigma.
    let y = var.height / 2;
    let peak = (0..smooth.width)
        .map(|x| lum(smooth.get(x, y)))
        .fold(0.0, f64::max);
    let sd = (0..var.width)
        .map(|x| lum(var.get(x, y)).sqrt())
        .fold(0.0, f64::max);
    let noise = 4.0 * 6f64.sqrt() * sd / peak;
    let (ss, fs) = (max_step(&smooth), max_step(&flat));
    assert!(ss < noise.max(0.01), "smooth step {ss} vs noise {noise}");
    assert!(fs > 5.0 * ss.max(0.01), "flat step {fs} vs smooth {ss}");
    // The smooth render follows Lambert's cosine on the true sphere: at the centre the
    // radiance is albedo/pi * E.
    let c = lum(smooth.get(48, 48));
    let want = 0.8 / std::f64::consts::PI * 3.0;
    assert!((c - want).abs() < 0.02 * want, "{c} vs {want}");

    let whitted = |crease: f64| {
        let s = WhittedSettings {
            aa: 1,
            crease_deg: crease,
            ..Default::default()
        };
        render_whitted(&scene, None, &s, &noop).unwrap()
    };
    let (ws, wf) = (max_step(&whitted(60.0)), max_step(&whitted(0.0)));
    assert!(ws < 0.01, "Whitted smooth step {ws}");
    assert!(
        wf > 5.0 * ws.max(0.01),
        "Whitted flat step {wf} vs smooth {ws}"
    );
}

/// A 2 x 2 quad in the z = 0 plane facing +z, with UVs 0..1 over it (v up).
pub(crate) fn uv_quad() -> cgnodes::types::Mesh {
    use cgnodes::types::{Attribute, Domain, Mesh};
    let p = vec![
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    let mut m = Mesh::from_triangles(p, &[[0, 1, 2], [0, 2, 3]]).unwrap();
    m.uvs = Some(Attribute {
        domain: Domain::Vertex,
        values: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
    });
    m
}

/// The quad with `material`, lit head-on by a directional light of irradiance 3, seen by
/// a 32 x 32 camera whose view lies inside it.
fn quad_scene(material: Material) -> Scene {
    Scene {
        objects: vec![SceneObject {
            mesh: Arc::new(uv_quad()),
            material: Some(Arc::new(material)),
        }],
        lights: vec![Light::Directional {
            direction: [0.0, 0.0, -1.0],
            color: [1.0; 3],
            intensity: 3.0,
        }],
        camera: Some(camera([0.0, 0.0, 3.0], 28.0, 32, 32)),
    }
}

fn rmse(a: &Image, b: &Image, k: f64) -> f64 {
    let mut s = 0.0;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for c in 0..3 {
            s += (p[c] as f64 * k - q[c] as f64).powi(2);
        }
    }
    (s / (3 * a.pixels.len()) as f64).sqrt()
}

/// A textured quad in the path tracer shows its texture as the rasterizer samples it: the
/// diffuse radiance times pi / E is the rasterizer's base-colour pass (texture times base
/// colour, bilinear at this magnification), within a small RMSE, while a constant grey
/// image of the texture's mean is far off. The Whitted tracer reads the same texture.
#[test]
fn textured_quad_matches_the_rasterizer() {
    use cgnodes::nodes::render::raster::{render, RasterOptions};
    // 8 x 8 texels of pseudo-random colours.
    let mut tex = Image::new(8, 8, [0.0, 0.0, 0.0, 1.0]);
    let mut h = 12345u32;
    for y in 0..8 {
        for x in 0..8 {
            let mut c = [0.0f32; 4];
            for ck in c.iter_mut().take(3) {
                h = h.wrapping_mul(1664525).wrapping_add(1013904223);
                *ck = 0.1 + 0.9 * (h >> 8) as f32 / 16_777_216.0;
            }
            c[3] = 1.0;
            tex.set(x, y, c);
        }
    }
    let scene = quad_scene(Material {
        base_color: [0.9, 0.8, 1.0],
        base_color_texture: Some(Arc::new(tex)),
        metallic: 0.0,
        roughness: 1.0,
        ..Default::default()
    });
    let cam = scene.camera.clone().unwrap();
    let opts = RasterOptions {
        samples_per_axis: 1,
        ..Default::default()
    };
    let raster = render(&scene, &cam, &opts).unwrap().base_color;
    let s = PathSettings {
        spp: 16,
        max_depth: 2,
        filter: Filter::Box,
        ..Default::default()
    };
    let (traced, _) = render_path(&scene, None, &s, &noop).unwrap();
    let k = std::f64::consts::PI / 3.0;
    let e = rmse(&traced, &raster, k);
    let mut grey = raster.clone();
    let n = raster.pixels.len() as f32;
    let m: [f32; 3] = std::array::from_fn(|c| raster.pixels.iter().map(|p| p[c]).sum::<f32>() / n);
    for p in &mut grey.pixels {
        p[..3].copy_from_slice(&m);
    }
    let e_grey = rmse(&grey, &raster, 1.0);
    assert!(
        e < 0.1 * e_grey && e < 0.02,
        "RMSE {e} (grey image: {e_grey})"
    );
    // Whitted: diffuse albedo/pi plus a 0.04 Blinn-Phong lobe, at normal incidence.
    let ws = WhittedSettings {
        aa: 1,
        ..Default::default()
    };
    let w = render_whitted(&scene, None, &ws, &noop).unwrap();
    let (px, py) = (9, 21);
    let want = raster.get(px, py)[1] as f64 / std::f64::consts::PI * 3.0
        + 0.04 * 9.0 * 3.0 / (8.0 * std::f64::consts::PI);
    let got = w.get(px, py)[1] as f64;
    assert!((got - want).abs() < 0.01 * want, "Whitted {got} vs {want}");
}

/// A constant tangent-space normal map tilting the normal by 40 degrees about the tangent
/// makes the head-on lit quad read albedo/pi E cos(40 deg) in both tracers.
#[test]
fn normal_map_tilts_the_shading_normal() {
    let a = 40f32.to_radians();
    let nmap = Image::new(2, 2, [0.5 + 0.5 * a.sin(), 0.5, 0.5 + 0.5 * a.cos(), 1.0]);
    let scene = quad_scene(Material {
        base_color: [0.8; 3],
        metallic: 0.0,
        roughness: 1.0,
        normal_map: Some(Arc::new(nmap)),
        ..Default::default()
    });
    let s = PathSettings {
        spp: 4,
        max_depth: 2,
        filter: Filter::Box,
        ..Default::default()
    };
    let (img, _) = render_path(&scene, None, &s, &noop).unwrap();
    let want = 0.8 / std::f64::consts::PI * 3.0 * (a as f64).cos();
    for (x, y) in [(5, 5), (16, 16), (27, 9)] {
        let got = img.get(x, y)[0] as f64;
        assert!(
            (got - want).abs() < 1e-3 * want,
            "({x}, {y}): {got} vs {want}"
        );
    }
    let ws = WhittedSettings {
        aa: 1,
        ..Default::default()
    };
    let w = render_whitted(&scene, None, &ws, &noop).unwrap();
    let got = w.get(16, 16)[0] as f64;
    // Plus the Blinn-Phong lobe 0.04 (s+8)/(8 pi) cos^s(theta_h) E cos(40) at s = 1.
    let spec =
        0.04 * 9.0 / (8.0 * std::f64::consts::PI) * (a as f64).cos() * 3.0 * (a as f64).cos();
    assert!(
        (got - want - spec).abs() < 0.01 * want,
        "Whitted {got} vs {}",
        want + spec
    );
}

/// A 24-segment sphere of albedo 0.5 seen from +z, with an environment light.
fn env_sphere(env: Light) -> Scene {
    Scene {
        objects: vec![SceneObject {
            mesh: Arc::new(sphere([0.0; 3], 1.0, 12, false)),
            material: Some(Arc::new(Material {
                base_color: [0.5; 3],
                ..Default::default()
            })),
        }],
        lights: vec![env],
        camera: Some(camera([0.0, 0.0, 4.0], 35.0, 32, 32)),
    }
}

/// A diffuse convex object in a constant environment of radiance L reflects albedo x L
/// everywhere (it sees the whole hemisphere of sky, and never itself): the mean over the
/// sphere's pixels is within 1% of it, for MIS and for environment sampling alone (BSDF
/// sampling alone is exact here since its weight is the albedo). Flat shading, so that
/// every hemisphere is the geometric one. The Whitted tracer's ambient gives the same.
#[test]
fn constant_environment_gives_albedo_times_radiance() {
    let env = Light::Environment {
        image: None,
        color: [0.8, 1.0, 1.2],
        intensity: 1.5,
        rotation_deg: 0.0,
    };
    let scene = env_sphere(env);
    let inside = |img: &Image| {
        // Pixels whose centre is well inside the sphere's silhouette (radius ~ 10 px).
        let mut m = [0.0f64; 3];
        let mut n = 0;
        for y in 0..32u32 {
            for x in 0..32u32 {
                let (dx, dy) = (x as f64 + 0.5 - 16.0, y as f64 + 0.5 - 16.0);
                if dx * dx + dy * dy < 64.0 {
                    let p = img.get(x, y);
                    for k in 0..3 {
                        m[k] += p[k] as f64;
                    }
                    n += 1;
                }
            }
        }
        assert!(n > 150, "{n} pixels");
        m.map(|v| v / n as f64)
    };
    let want = [0.5 * 0.8 * 1.5, 0.5 * 1.5, 0.5 * 1.2 * 1.5];
    for strategy in [Strategy::Mis, Strategy::Nee] {
        let s = PathSettings {
            spp: 64,
            max_depth: 4,
            filter: Filter::Box,
            strategy,
            crease_deg: 0.0,
            ..Default::default()
        };
        let (img, _) = render_path(&scene, None, &s, &noop).unwrap();
        let m = inside(&img);
        for k in 0..3 {
            assert!(
                (m[k] - want[k]).abs() < 0.01 * want[k],
                "{strategy:?}: {m:?} vs {want:?}"
            );
        }
        // The background shows the environment itself.
        let b = img.get(0, 0);
        assert!((b[1] - 1.5).abs() < 1e-5, "{b:?}");
    }
    let ws = WhittedSettings {
        aa: 1,
        crease_deg: 0.0,
        ..Default::default()
    };
    let w = render_whitted(&scene, None, &ws, &noop).unwrap();
    // Diffuse ambient albedo x mean radiance, plus nothing else (no other lights).
    let c = w.get(16, 16)[1] as f64;
    assert!((c - want[1]).abs() < 1e-4, "Whitted {c} vs {}", want[1]);
}

/// Under the HDR sky of `assets/envmaps/sky.exr` (a sun 200 times brighter than the
/// sky), environment sampling alone and BSDF sampling alone converge to the same image as
/// MIS: the whole-image means and the lower half's agree within 3%.
#[test]
fn environment_and_bsdf_sampling_agree() {
    use cgnodes::nodes::image::image_load::{decode_image, ColorSpace};
    let bytes = std::fs::read(crate::common::root().join("assets/envmaps/sky.exr")).unwrap();
    let sky = decode_image(&bytes, ColorSpace::Raw).unwrap();
    assert_eq!((sky.width, sky.height), (64, 32));
    let env = Light::Environment {
        image: Some(Arc::new(sky)),
        color: [1.0; 3],
        intensity: 1.0,
        rotation_deg: 25.0,
    };
    let mut scene = env_sphere(env);
    // A ground plane below the sphere (it shadows and is lit by bounce light), and the
    // camera a little above, looking down.
    let ground = cgnodes::types::Mesh::from_triangles(
        vec![
            [-4.0, -1.0, -4.0],
            [4.0, -1.0, -4.0],
            [4.0, -1.0, 4.0],
            [-4.0, -1.0, 4.0],
        ],
        &[[0, 2, 1], [0, 3, 2]],
    )
    .unwrap();
    scene.objects.push(SceneObject {
        mesh: Arc::new(ground),
        material: Some(Arc::new(Material {
            base_color: [0.6, 0.5, 0.4],
            ..Default::default()
        })),
    });
    let mut cam = camera([0.0, 1.5, 4.0], 45.0, 24, 24);
    cam.target = [0.0, -0.3, 0.0];
    let mut means = Vec::new();
    for (strategy, spp) in [
        (Strategy::Mis, 256),
        (Strategy::Nee, 256),
        (Strategy::Bsdf, 1024),
    ] {
        let s = PathSettings {
            spp,
            max_depth: 3,
            filter: Filter::Box,
            strategy,
            ..Default::default()
        };
        let (img, _) = render_path(&scene, Some(&cam), &s, &noop).unwrap();
        // Whole image and its lower half.
        let (whole, low) = (mean(&img), patch_mean(&img, [12, 24], [0, 24]));
        means.push((strategy, whole, low));
    }
    let (_, w0, l0) = means[0];
    for (s, w, l) in &means[1..] {
        for k in 0..3 {
            assert!(
                (w[k] - w0[k]).abs() < 0.03 * w0[k],
                "{s:?} whole {w:?} vs MIS {w0:?}"
            );
            assert!(
                (l[k] - l0[k]).abs() < 0.03 * l0[k],
                "{s:?} lower half {l:?} vs MIS {l0:?}"
            );
        }
    }
}
