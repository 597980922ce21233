//! The G-buffer passes (`nodes/render/gbuffer/`) against references: deferred lighting
//! reproduces `render_raster`'s own colour from its passes (with and without shadow maps),
//! the environment pass shows the environment along each camera ray, and refraction leaves
//! the environment as it is through a flat surface of index 1 and turns it over in the
//! centre of a glass sphere. SSAO and the camera recovery are in `ssao`.

use crate::common::run_node;
use cgnodes::nodes::mesh::mesh_plane::plane_mesh;
use cgnodes::nodes::render::gbuffer::deferred_lighting::{deferred_lighting, GBuffer, Lighting};
use cgnodes::nodes::render::gbuffer::environment_pass::environment_pass;
use cgnodes::nodes::render::gbuffer::shadow_mapping::{map_from_image, scene_bounds, shadow_maps};
use cgnodes::nodes::render::gbuffer::transparent_refraction::{transparent_refraction, Refraction};
use cgnodes::nodes::render::gbuffer::Sky;
use cgnodes::nodes::render::raster::{render, RasterOptions};
use cgnodes::nodes::trace::environment::Environment;
use cgnodes::types::*;
use std::sync::Arc;

mod ssao;

/// A UV sphere of radius `r` at `c` with exact vertex normals.
fn sphere(c: [f64; 3], r: f64, nu: u32, nv: u32) -> Mesh {
    let mut pos = Vec::new();
    let mut nrm = Vec::new();
    for j in 0..=nv {
        let t = std::f64::consts::PI * j as f64 / nv as f64;
        for i in 0..=nu {
            let p = 2.0 * std::f64::consts::PI * i as f64 / nu as f64;
            let n = [t.sin() * p.cos(), t.cos(), t.sin() * p.sin()];
            pos.push([c[0] + r * n[0], c[1] + r * n[1], c[2] + r * n[2]]);
            nrm.push(n);
        }
    }
    let mut tris = Vec::new();
    let row = nu + 1;
    for j in 0..nv {
        for i in 0..nu {
            let (a, b, cc, d) = (
                j * row + i,
                j * row + i + 1,
                (j + 1) * row + i + 1,
                (j + 1) * row + i,
            );
            tris.push([a, b, cc]);
            tris.push([a, cc, d]);
        }
    }
    let mut m = Mesh::from_triangles(pos, &tris).unwrap();
    m.normals = Some(Attribute {
        domain: Domain::Vertex,
        values: nrm,
    });
    m
}

fn obj(m: Mesh, mat: Option<Material>) -> SceneObject {
    SceneObject {
        mesh: Arc::new(m),
        material: mat.map(Arc::new),
    }
}

fn rmse(a: &Image, b: &Image) -> f64 {
    let s: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| (0..3).map(|k| ((p[k] - q[k]) as f64).powi(2)).sum::<f64>())
        .sum();
    (s / (3 * a.pixels.len()) as f64).sqrt()
}

/// A sphere over a ground plane, lit by a point and a directional light.
fn lit_scene() -> (Scene, Camera) {
    let mat = Material {
        base_color: [0.8, 0.5, 0.3],
        metallic: 0.4,
        roughness: 0.35,
        ..Default::default()
    };
    let ground = Material {
        base_color: [0.6, 0.65, 0.7],
        ..mat.clone()
    };
    let cam = Camera {
        eye: [1.8, 1.6, 2.6],
        target: [0.0, 0.4, 0.0],
        fov_deg: 40.0,
        width: 96,
        height: 72,
        ..Default::default()
    };
    let scene = Scene {
        objects: vec![
            obj(sphere([0.0, 0.6, 0.0], 0.6, 32, 16), Some(mat)),
            obj(plane_mesh(4.0, [0.0, 0.0, 0.0], 2, 1.0), Some(ground)),
        ],
        lights: vec![
            Light::Point {
                position: [1.2, 2.5, 1.0],
                color: [1.0, 0.95, 0.9],
                intensity: 6.0,
            },
            Light::Directional {
                direction: [-0.5, -1.0, -0.3],
                color: [0.8, 0.85, 1.0],
                intensity: 0.6,
            },
        ],
        camera: Some(cam.clone()),
    };
    (scene, cam)
}

/// At one sample per pixel, lighting render_raster's passes gives render_raster's colour:
/// what differs is f32 rounding of the passes, and with shadows the bias, which uses the
/// shading normal where the rasterizer uses the geometric one.
#[test]
fn deferred_lighting_reproduces_the_rasterizer() {
    let (scene, cam) = lit_scene();
    let set = Lighting {
        metallic: 0.4,
        roughness: 0.35,
        ..Default::default()
    };
    for shadows in [false, true] {
        let opts = RasterOptions {
            samples_per_axis: 1,
            shadows,
            shadow_resolution: 1024,
            ..Default::default()
        };
        let out = render(&scene, &cam, &opts).unwrap();
        let gb = GBuffer {
            position: &out.position,
            normal: &out.normal,
            base_color: &out.base_color,
            metallic_roughness: None,
        };
        let maps = if shadows {
            let bounds = scene_bounds(&scene).unwrap();
            shadow_maps(&scene, 1024)
                .unwrap()
                .iter()
                .zip(&scene.lights)
                .map(|(img, l)| map_from_image(img, l, bounds).unwrap())
                .collect()
        } else {
            Vec::new()
        };
        let lit = deferred_lighting(gb, &cam, &scene.lights, &maps, &set);
        let e = rmse(&lit, &out.color);
        let max = lit
            .pixels
            .iter()
            .zip(&out.color.pixels)
            .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0f32, f32::max))
            .fold(0.0f32, f32::max);
        println!("shadows {shadows}: RMSE {e:.2e}, max {max:.2e}");
        if shadows {
            assert!(e < 5e-3, "RMSE {e}");
        } else {
            assert!(e < 1e-5 && max < 1e-4, "RMSE {e}, max {max}");
        }
    }
    // The shadows are really there: the unshadowed lighting is brighter under the sphere.
    let opts = RasterOptions {
        samples_per_axis: 1,
        shadows: true,
        shadow_resolution: 1024,
        ..Default::default()
    };
    let out = render(&scene, &cam, &opts).unwrap();
    let gb = GBuffer {
        position: &out.position,
        normal: &out.normal,
        base_color: &out.base_color,
        metallic_roughness: None,
    };
    let unshadowed = deferred_lighting(gb, &cam, &scene.lights, &[], &set);
    assert!(rmse(&unshadowed, &out.color) > 0.02);
}

fn sky_image() -> Image {
    // R = 0.5 + 0.5 sin(2 pi (u - 1/2)): rises with the azimuth towards +x in front (-z),
    // continuous across the seam behind.
    let (w, h) = (512u32, 256u32);
    let mut img = Image::new(w, h, [0.0; 4]);
    for y in 0..h {
        for x in 0..w {
            let u = (x as f32 + 0.5) / w as f32;
            let r = 0.5 + 0.5 * (2.0 * std::f32::consts::PI * (u - 0.5)).sin();
            img.set(x, y, [r, 0.2 + 0.5 * y as f32 / h as f32, 0.3, 1.0]);
        }
    }
    img
}

fn env_light(image: Option<Image>, color: [f64; 3]) -> Light {
    Light::Environment {
        image: image.map(Arc::new),
        color,
        intensity: 1.0,
        rotation_deg: 30.0,
    }
}

/// The camera ray through pixel (x, y) of a camera at the origin looking down -z, by hand.
fn ray(cam: &Camera, x: u32, y: u32) -> [f32; 3] {
    let f = 0.5 * cam.height as f64 / (0.5 * cam.fov_deg.to_radians()).tan();
    let d = [
        (x as f64 + 0.5 - 0.5 * cam.width as f64) / f,
        (0.5 * cam.height as f64 - y as f64 - 0.5) / f,
        -1.0,
    ];
    let l = (d[0] * d[0] + d[1] * d[1] + 1.0).sqrt();
    d.map(|c| (c / l) as f32)
}

#[test]
fn environment_pass_shows_the_environment_along_camera_rays() {
    let cam = Camera {
        eye: [0.0; 3],
        target: [0.0, 0.0, -1.0],
        fov_deg: 70.0,
        width: 40,
        height: 30,
        ..Default::default()
    };
    // A depth pass with a hit in the left half only.
    let mut depth = Image::new(40, 30, [0.0; 4]);
    let color = Image::new(40, 30, [0.25, 0.5, 0.75, 1.0]);
    for y in 0..30 {
        for x in 0..20 {
            depth.set(x, y, [2.0, 2.0, 2.0, 1.0]);
        }
    }
    let c = [0.3, 0.6, 0.9];
    let flat = environment_pass(
        &color,
        &depth,
        &cam,
        &Sky::new(&[env_light(None, c)], [0.0; 3]),
    );
    let img = sky_image();
    let lights = [env_light(Some(img.clone()), [1.0; 3])];
    let out = environment_pass(&color, &depth, &cam, &Sky::new(&lights, [0.0; 3]));
    let env = Environment::new(Some(&img), [1.0; 3], 30.0);
    for y in 0..30 {
        for x in 0..40 {
            if x < 20 {
                assert_eq!(out.get(x, y), [0.25, 0.5, 0.75, 1.0]);
            } else {
                assert_eq!(flat.get(x, y), [0.3, 0.6, 0.9, 1.0]);
                let e = env.eval(ray(&cam, x, y));
                let o = out.get(x, y);
                assert!(
                    (0..3).all(|k| (o[k] - e[k]).abs() < 1e-6),
                    "({x}, {y}): {o:?} {e:?}"
                );
            }
        }
    }
}

/// The G-buffer of `scene` seen through `cam`, one sample per pixel.
fn gbuffer_of(scene: &Scene, cam: &Camera) -> cgnodes::nodes::render::raster::RenderOutput {
    render(
        scene,
        cam,
        &RasterOptions {
            samples_per_axis: 1,
            ..Default::default()
        },
    )
    .unwrap()
}

#[test]
fn refraction_through_index_one_keeps_the_environment_and_a_glass_sphere_turns_it_over() {
    let cam = Camera {
        eye: [0.0; 3],
        target: [0.0, 0.0, -1.0],
        fov_deg: 50.0,
        width: 64,
        height: 48,
        ..Default::default()
    };
    let img = sky_image();
    let lights = [env_light(Some(img.clone()), [1.0; 3])];
    let sky = Sky::new(&lights, [0.0; 3]);
    let env = Environment::new(Some(&img), [1.0; 3], 30.0);
    let no_highlight = |ior| Refraction {
        ior,
        highlight: 0.0,
        ..Default::default()
    };
    // A slab face z = -3 filling the view: with ior 1 the view ray goes straight through,
    // and only Schlick's term (1 - cos)^5 (r0 = 0) mixes in the reflection.
    let slab = Mesh::from_triangles(
        vec![
            [-9.0, -9.0, -3.0],
            [9.0, -9.0, -3.0],
            [9.0, 9.0, -3.0],
            [-9.0, 9.0, -3.0],
        ],
        &[[0, 1, 2], [0, 2, 3]],
    )
    .unwrap();
    let g = gbuffer_of(
        &Scene {
            objects: vec![obj(slab, None)],
            ..Default::default()
        },
        &cam,
    );
    let out = transparent_refraction(
        &g.position,
        &g.normal,
        &g.depth,
        None,
        cam.eye,
        &lights,
        &sky,
        &no_highlight(1.0),
    );
    for y in 0..48 {
        for x in 0..64 {
            let d = ray(&cam, x, y);
            let cos = -d[2];
            let f = (1.0 - cos).powi(5);
            let (t, r) = (env.eval(d), env.eval([d[0], d[1], -d[2]]));
            let o = out.get(x, y);
            for k in 0..3 {
                let want = (1.0 - f) * t[k] + f * r[k];
                assert!((o[k] - want).abs() < 2e-4, "({x}, {y}): {o:?} vs {want}");
                assert!((o[k] - t[k]).abs() <= f * (t[k] - r[k]).abs() + 2e-4);
            }
        }
    }
    // A sphere of radius 1 three units ahead: along the middle row, the environment's red
    // rises to the right through index 1 and falls to the right through glass (1.5).
    let g = gbuffer_of(
        &Scene {
            objects: vec![obj(sphere([0.0, 0.0, -3.0], 1.0, 96, 48), None)],
            ..Default::default()
        },
        &cam,
    );
    let row = |ior: f64, exit: bool| {
        let set = Refraction {
            exit,
            ..no_highlight(ior)
        };
        let out = transparent_refraction(
            &g.position,
            &g.normal,
            &g.depth,
            None,
            cam.eye,
            &lights,
            &sky,
            &set,
        );
        // The sphere spans about +-18 pixels around x = 32; take its central half.
        (23..41).map(|x| out.get(x, 24)[0]).collect::<Vec<f32>>()
    };
    let (straight, glass, front_only) = (row(1.0, true), row(1.5, true), row(1.5, false));
    println!("ior 1: {straight:?}\nior 1.5: {glass:?}\nior 1.5, front only: {front_only:?}");
    assert!(straight.windows(2).all(|w| w[1] >= w[0] - 1e-3));
    assert!(straight[straight.len() - 1] > straight[0] + 0.05);
    assert!(glass.windows(2).all(|w| w[1] <= w[0] + 1e-3));
    assert!(glass[0] > glass[glass.len() - 1] + 0.05);
    // One refraction (the course's shader) nearly cancels the view ray's spread here:
    // the red changes less across the row than through index 1.
    let spread = |v: &[f32]| (v[v.len() - 1] - v[0]).abs();
    assert!(spread(&front_only) < 0.5 * spread(&straight));
}

/// The nodes' errors name the socket at fault.
#[test]
fn pass_nodes_name_the_socket_at_fault() {
    let files = cgnodes::node::FileEnv::default();
    let img = |w, h| Value::Image(Arc::new(Image::new(w, h, [0.0, 0.0, 1.0, 1.0])));
    let (scene, cam) = lit_scene();
    let no_cam = Scene {
        camera: None,
        ..scene.clone()
    };
    // deferred lighting over 96x72 G-buffer images, the normal image `normal_w` wide
    let deferred = |scene: &Scene, normal_w: u32, extra: Vec<(&'static str, Value)>| {
        let mut inputs = vec![
            ("scene", Value::Scene(Arc::new(scene.clone()))),
            ("position", img(96, 72)),
            ("normal", img(normal_w, 72)),
            ("base_color", img(96, 72)),
        ];
        inputs.extend(extra);
        run_node("deferred_lighting", inputs, &files).unwrap_err()
    };
    let e = deferred(&no_cam, 96, vec![]);
    assert!(e.contains("camera"), "{e}");
    let e = deferred(&scene, 95, vec![]);
    assert!(e.contains("normal") && e.contains("95x72"), "{e}");
    let e = deferred(
        &scene,
        96,
        vec![(
            "shadows",
            Value::from(vec![Arc::new(Image::new(8, 8, [0.0; 4]))]),
        )],
    );
    assert!(e.contains("shadows"), "{e}");
    let e = run_node(
        "ssao",
        vec![
            ("position", img(96, 72)),
            ("depth", img(96, 70)),
            ("camera", Value::Camera(Arc::new(cam.clone()))),
        ],
        &files,
    )
    .unwrap_err();
    assert!(e.contains("depth"), "{e}");
    // No environment light: the documented fallback colour, with a warning.
    let (outs, logs) = run_node(
        "environment_pass",
        vec![
            ("scene", Value::Scene(Arc::new(scene))),
            ("color", img(96, 72)),
            ("depth", img(96, 72)),
        ],
        &files,
    )
    .unwrap();
    assert!(logs.iter().any(|l| l.starts_with("warning:")), "{logs:?}");
    assert!(outs.contains_key("color"));
}
