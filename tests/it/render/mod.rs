//! Rasterizer tests with analytic answers: coverage and depth, Lambert shading, shadows,
//! acne, normal maps, mipmaps, culling, determinism; the golden image and pass selection in
//! `golden`.

use cgnodes::nodes::mesh::mesh_plane::plane_mesh;
use cgnodes::nodes::render::raster::{release_scratch, render, AntiAliasing, RasterOptions};
use cgnodes::types::*;
use std::sync::Arc;

mod golden;

fn tri_mesh(p: Vec<[f64; 3]>) -> Arc<Mesh> {
    Arc::new(Mesh::from_triangles(p, &[[0, 1, 2]]).unwrap())
}

fn opts1() -> RasterOptions {
    RasterOptions {
        samples_per_axis: 1,
        background: [0.0; 3],
        ..Default::default()
    }
}

fn px(img: &Image, x: u32, y: u32) -> [f32; 4] {
    img.get(x, y)
}

/// Camera at (0,0,3) looking down -z with a 90 degree vertical field of view on 64x64:
/// pixel centre (i + 0.5, j + 0.5) looks through world (x, y) = ((i+.5-32)/32 * d,
/// (32-j-.5)/32 * d) at distance d.
fn front_camera() -> Camera {
    Camera {
        fov_deg: 90.0,
        width: 64,
        height: 64,
        ..Default::default()
    }
}

fn pixel_to_plane(i: u32, j: u32, d: f64) -> (f64, f64) {
    (
        (i as f64 + 0.5 - 32.0) / 32.0 * d,
        (32.0 - j as f64 - 0.5) / 32.0 * d,
    )
}

#[test]
fn triangle_coverage_and_depth_at_chosen_pixels() {
    // Triangle x >= -1, y >= -1, x + y <= 0 in the plane z = 0, 3 units from the eye.
    let scene = Scene {
        objects: vec![SceneObject {
            mesh: tri_mesh(vec![[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [-1.0, 1.0, 0.0]]),
            material: None,
        }],
        ..Default::default()
    };
    let out = render(&scene, &front_camera(), &opts1()).unwrap();
    let mut checked = 0;
    for j in 0..64 {
        for i in 0..64 {
            let (x, y) = pixel_to_plane(i, j, 3.0);
            let margin = 0.02; // stay clear of the edges
            let inside = x > -1.0 + margin && y > -1.0 + margin && x + y < -margin;
            let outside = x < -1.0 - margin || y < -1.0 - margin || x + y > margin;
            let d = px(&out.depth, i, j);
            if inside {
                assert_eq!(d[3], 1.0, "pixel {i},{j} should be covered");
                assert!((d[0] - 3.0).abs() < 1e-5, "depth {}", d[0]);
                checked += 1;
            } else if outside {
                assert_eq!(d[3], 0.0, "pixel {i},{j} should be empty");
            }
        }
    }
    // About an eighth of the image: (2 x 2 / 2) / (6 x 6) * 4096 = 227 pixels.
    assert!(checked > 180 && checked < 240, "{checked}");
}

#[test]
fn slanted_triangle_depth_is_perspective_correct() {
    // Plane z = -y/2 (tilted away upwards); the view ray through a pixel meets it where
    // 3 - t = -(y0 t)/2 with direction (x0, y0, -1): t = 3 / (1 - y0/2); depth = t.
    let scene = Scene {
        objects: vec![SceneObject {
            mesh: tri_mesh(vec![[-3.0, -2.0, 1.0], [3.0, -2.0, 1.0], [0.0, 2.0, -1.0]]),
            material: None,
        }],
        ..Default::default()
    };
    let out = render(&scene, &front_camera(), &opts1()).unwrap();
    for (i, j) in [(32, 30), (32, 45), (25, 40), (38, 36)] {
        let (x0, y0) = pixel_to_plane(i, j, 1.0);
        let t = 3.0 / (1.0 - y0 / 2.0);
        let d = px(&out.depth, i, j);
        assert_eq!(d[3], 1.0);
        assert!(
            (d[0] as f64 - t).abs() < 1e-4,
            "pixel {i},{j}: {} vs {t}",
            d[0]
        );
        let p = px(&out.position, i, j);
        assert!((p[0] as f64 - x0 * t).abs() < 1e-4 && (p[1] as f64 - y0 * t).abs() < 1e-4);
    }
}

/// A camera 4 units above the origin looking straight down at a ground plane.
fn top_camera() -> Camera {
    Camera {
        eye: [0.0, 4.0, 0.0],
        target: [0.0; 3],
        up: [0.0, 0.0, -1.0],
        fov_deg: 60.0,
        width: 48,
        height: 48,
        ..Default::default()
    }
}

fn ground(base: [f64; 3]) -> SceneObject {
    SceneObject {
        mesh: Arc::new(plane_mesh(8.0, [0.0; 3], 4, 1.0)),
        material: Some(Arc::new(Material {
            base_color: base,
            ..Default::default()
        })),
    }
}

#[test]
fn lambert_lit_plane_matches_the_formula() {
    let base = [0.5, 0.4, 0.2];
    let s = 0.5f64.sqrt();
    let scene = Scene {
        objects: vec![ground(base)],
        lights: vec![
            Light::Directional {
                direction: [0.0, -s, -s],
                color: [1.0, 1.0, 0.5],
                intensity: 2.0,
            },
            Light::Point {
                position: [1.0, 2.0, 0.0],
                color: [1.0; 3],
                intensity: 3.0,
            },
        ],
        ..Default::default()
    };
    let out = render(&scene, &top_camera(), &opts1()).unwrap();
    for (i, j) in [(24, 24), (5, 7), (40, 30), (12, 44)] {
        let p = px(&out.position, i, j);
        let (x, z) = (p[0] as f64, p[2] as f64);
        assert!(p[1].abs() < 1e-6);
        // Directional: cos = s. Point: r^2 = (x-1)^2 + 4 + z^2, cos = 2/r, E = 3/r^2.
        let r2 = (x - 1.0).powi(2) + 4.0 + z * z;
        let point = 3.0 / r2 * 2.0 / r2.sqrt();
        let c = px(&out.color, i, j);
        for k in 0..3 {
            let dir_e = 2.0 * [1.0, 1.0, 0.5][k] * s;
            let want = base[k] * (0.2 + dir_e + point);
            assert!(
                (c[k] as f64 - want).abs() < 1e-5,
                "{i},{j}[{k}]: {} vs {want}",
                c[k]
            );
        }
    }
}

fn shadow_scene(base: [f64; 3]) -> Scene {
    // A 1x1 blocker at height 1 over the ground, lit straight from above.
    let blocker = Mesh::from_triangles(
        vec![
            [-0.5, 1.0, -0.5],
            [0.5, 1.0, -0.5],
            [0.5, 1.0, 0.5],
            [-0.5, 1.0, 0.5],
        ],
        &[[0, 2, 1], [0, 3, 2]],
    )
    .unwrap();
    Scene {
        objects: vec![
            ground(base),
            SceneObject {
                mesh: Arc::new(blocker),
                material: None,
            },
        ],
        lights: vec![Light::Directional {
            direction: [0.0, -1.0, 0.0],
            color: [1.0; 3],
            intensity: 1.0,
        }],
        ..Default::default()
    }
}

#[test]
fn point_in_shadow_receives_only_ambient() {
    let base = [0.6, 0.3, 0.9];
    let scene = shadow_scene(base);
    // Look at the ground under the blocker from the side, below the blocker's height.
    let cam = Camera {
        eye: [0.0, 0.5, 3.0],
        target: [0.0, 0.0, 0.0],
        width: 64,
        height: 64,
        ..Default::default()
    };
    let out = render(&scene, &cam, &opts1()).unwrap();
    let mut in_shadow = 0;
    let mut lit = 0;
    for j in 0..64 {
        for i in 0..64 {
            let p = px(&out.position, i, j);
            if p[3] == 0.0 || p[1].abs() > 1e-6 {
                continue;
            }
            let c = px(&out.color, i, j);
            let (x, z) = (p[0], p[2]);
            if x.abs() < 0.4 && z.abs() < 0.4 {
                in_shadow += 1;
                for k in 0..3 {
                    assert!((c[k] as f64 - 0.2 * base[k]).abs() < 1e-6, "{c:?}");
                }
            } else if x.abs() > 0.6 || z.abs() > 0.6 {
                lit += 1;
                for k in 0..3 {
                    assert!((c[k] as f64 - 1.2 * base[k]).abs() < 1e-5, "{c:?}");
                }
            }
        }
    }
    assert!(in_shadow > 20 && lit > 100, "{in_shadow} {lit}");
}

#[test]
fn unoccluded_lit_plane_has_no_shadowed_pixels() {
    // Lights at 0, 45 and 70 degrees from the normal, one point light; shadows on and off
    // must agree on every pixel.
    for (dir, point) in [
        ([0.0, -1.0, 0.0], [0.0, 3.0, 0.0]),
        ([1.0, -1.0, 0.3], [2.0, 1.0, -1.0]),
        ([2.75, -1.0, 0.0], [-3.0, 0.7, 2.0]),
    ] {
        let scene = Scene {
            objects: vec![ground([0.7; 3])],
            lights: vec![
                Light::Directional {
                    direction: dir,
                    color: [1.0; 3],
                    intensity: 1.0,
                },
                Light::Point {
                    position: point,
                    color: [1.0; 3],
                    intensity: 2.0,
                },
            ],
            ..Default::default()
        };
        let cam = Camera {
            eye: [0.5, 3.0, 4.0],
            target: [0.0; 3],
            width: 64,
            height: 64,
            ..Default::default()
        };
        for res in [256, 2048] {
            let with = render(
                &scene,
                &cam,
                &RasterOptions {
                    shadow_resolution: res,
                    ..opts1()
                },
            )
            .unwrap();
            let without = render(
                &scene,
                &cam,
                &RasterOptions {
                    shadows: false,
                    ..opts1()
                },
            )
            .unwrap();
            let shadowed = with
                .color
                .pixels
                .iter()
                .zip(&without.color.pixels)
                .filter(|(a, b)| a != b)
                .count();
            assert_eq!(shadowed, 0, "light {dir:?} / {point:?} at {res}");
        }
    }
}

#[test]
fn flat_normal_map_changes_nothing() {
    let mk = |nm: Option<Arc<Image>>| Scene {
        objects: vec![SceneObject {
            mesh: Arc::new(plane_mesh(4.0, [0.0; 3], 3, 2.0)),
            material: Some(Arc::new(Material {
                metallic: 0.5,
                roughness: 0.4,
                normal_map: nm,
                ..Default::default()
            })),
        }],
        lights: vec![Light::Point {
            position: [1.0, 2.0, 1.0],
            color: [1.0; 3],
            intensity: 5.0,
        }],
        camera: Some(Camera {
            eye: [0.0, 2.0, 3.0],
            width: 48,
            height: 48,
            ..Default::default()
        }),
    };
    let flat = Arc::new(Image::new(8, 8, [0.5, 0.5, 1.0, 1.0]));
    let a = mk(None);
    let b = mk(Some(flat));
    let cam = a.camera.clone().unwrap();
    let ra = render(&a, &cam, &RasterOptions::default()).unwrap();
    let rb = render(&b, &cam, &RasterOptions::default()).unwrap();
    assert_eq!(ra.color.pixels, rb.color.pixels);
    assert_eq!(ra.normal.pixels, rb.normal.pixels);
    // And a tilted normal map does change the shading (the test can fail).
    let tilted = Arc::new(Image::new(8, 8, [0.8, 0.5, 0.9, 1.0]));
    let rc = render(&mk(Some(tilted)), &cam, &RasterOptions::default()).unwrap();
    assert_ne!(ra.color.pixels, rc.color.pixels);
    // Tangent +x (u): the normal tilts towards +x.
    let n = rc.normal.get(24, 30);
    assert!(n[0] > 0.3, "{n:?}");
}

fn checker(n: u32, cells: u32) -> Image {
    let mut img = Image::new(n, n, [0.0, 0.0, 0.0, 1.0]);
    for y in 0..n {
        for x in 0..n {
            if (x * cells / n + y * cells / n).is_multiple_of(2) {
                img.set(x, y, [1.0; 4]);
            }
        }
    }
    img
}

#[test]
fn mipmaps_keep_a_far_checkerboard_from_aliasing() {
    // A huge plane repeating a fine checkerboard, seen at a grazing angle: the top rows
    // see many checks per pixel. With mipmaps they are near the mean grey; point-sampled
    // level 0 gives noisy black and white (moire).
    let tex = Arc::new(checker(64, 16));
    let scene = Scene {
        objects: vec![SceneObject {
            mesh: Arc::new(plane_mesh(200.0, [0.0; 3], 1, 200.0)),
            material: Some(Arc::new(Material {
                base_color: [1.0; 3],
                base_color_texture: Some(tex),
                ..Default::default()
            })),
        }],
        ..Default::default()
    };
    let cam = Camera {
        eye: [0.0, 1.0, 0.0],
        target: [0.0, 0.8, -10.0],
        width: 96,
        height: 64,
        far: 1e4,
        ..Default::default()
    };
    let opts = |mip| RasterOptions {
        ambient: 1.0,
        mipmaps: mip,
        ..opts1()
    };
    let spread = |img: &Image| {
        // Rows just under the horizon (the plane is far there).
        let mut v = Vec::new();
        for j in 0..64 {
            for i in 0..96 {
                let p = img.get(i, j);
                if p[3] > 0.0 {
                    v.push(p[0] as f64);
                }
            }
            if v.len() > 500 {
                break;
            }
        }
        let m = v.iter().sum::<f64>() / v.len() as f64;
        (
            m,
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64).sqrt(),
        )
    };
    let with = render(&scene, &cam, &opts(true)).unwrap();
    let without = render(&scene, &cam, &opts(false)).unwrap();
    let (m1, s1) = spread(&with.base_color);
    let (_, s0) = spread(&without.base_color);
    assert!((m1 - 0.5).abs() < 0.1, "mean {m1}");
    assert!(s1 < 0.1 && s0 > 0.3, "std with mipmaps {s1}, without {s0}");
}

#[test]
fn backface_culling_drops_only_faces_seen_from_behind() {
    // Counter-clockwise seen from the camera at +z: front face.
    let front = vec![[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]];
    let back = vec![[-1.0, -1.0, 0.0], [0.0, 1.0, 0.0], [1.0, -1.0, 0.0]];
    for (p, visible_when_culled) in [(front, true), (back, false)] {
        let scene = Scene::from_mesh(tri_mesh(p));
        let culled = render(
            &scene,
            &front_camera(),
            &RasterOptions {
                cull_backfaces: true,
                ..opts1()
            },
        )
        .unwrap();
        let plain = render(&scene, &front_camera(), &opts1()).unwrap();
        assert_eq!(plain.depth.get(32, 32)[3], 1.0);
        assert_eq!(culled.depth.get(32, 32)[3] == 1.0, visible_when_culled);
        // Two-sided lighting: the normal pass faces the camera either way.
        assert!(plain.normal.get(32, 32)[2] > 0.99);
    }
}

#[test]
fn antialiasing_blends_edges_and_is_deterministic() {
    let scene = Scene::from_mesh(tri_mesh(vec![
        [-1.0, -1.0, 0.0],
        [1.3, -1.0, 0.0],
        [-1.0, 1.1, 0.0],
    ]));
    let cam = front_camera();
    let mut o = RasterOptions {
        samples_per_axis: 4,
        ambient: 1.0,
        ..opts1()
    };
    let a = render(&scene, &cam, &o).unwrap();
    let partial = a
        .color
        .pixels
        .iter()
        .filter(|p| p[0] > 0.01 && p[0] < 0.79)
        .count();
    assert!(partial > 20, "edge pixels blend: {partial}");
    // Coverage fractions are multiples of 1/16.
    for p in &a.color.pixels {
        let q = p[0] as f64 / 0.8 * 16.0;
        assert!((q - q.round()).abs() < 1e-4);
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let b = pool.install(|| render(&scene, &cam, &o).unwrap());
    assert_eq!(a.color.pixels, b.color.pixels);
    // Supersampling agrees with multisampling on a flat unlit colour.
    o.aa = AntiAliasing::Supersampling;
    let c = render(&scene, &cam, &o).unwrap();
    for (x, y) in a.color.pixels.iter().zip(&c.color.pixels) {
        assert!((x[0] - y[0]).abs() < 1e-6);
    }
}

/// The rasterizer keeps its big buffers (setups, shadow maps, flattened scene) from one render
/// to the next: a render after a larger one with other lights, and one after the buffers are
/// freed, give the same bytes in every pass as the first.
#[test]
fn renders_reusing_kept_buffers_match_fresh_ones() {
    // The light slanted so the camera above sees the blocker's shadow beside it.
    let mut small = shadow_scene([0.6, 0.3, 0.9]);
    small.lights = vec![Light::Directional {
        direction: [0.6, -1.0, 0.3],
        color: [1.0; 3],
        intensity: 1.0,
    }];
    let cam = top_camera();
    let o = RasterOptions {
        shadow_resolution: 256,
        ..opts1()
    };
    let first = render(&small, &cam, &o).unwrap();
    // More triangles, a point light's cube map, bigger maps and image.
    let mut big = shadow_scene([0.2, 0.8, 0.4]);
    big.objects.push(SceneObject {
        mesh: Arc::new(plane_mesh(3.0, [0.0, 0.5, 0.0], 12, 1.0)),
        material: None,
    });
    big.lights.push(Light::Point {
        position: [1.0, 2.0, 0.5],
        color: [1.0; 3],
        intensity: 3.0,
    });
    let big_cam = Camera {
        width: 96,
        height: 80,
        ..top_camera()
    };
    let big_o = RasterOptions {
        shadow_resolution: 512,
        samples_per_axis: 2,
        ..o.clone()
    };
    assert!(render(&big, &big_cam, &big_o).unwrap().triangles > first.triangles);
    let again = render(&small, &cam, &o).unwrap();
    release_scratch();
    let fresh = render(&small, &cam, &o).unwrap();
    // Lit and shadowed pixels both present, so stale depths or setups would show.
    let ambient = first.color.pixels.iter().filter(|c| c[0] < 0.2).count();
    assert!(ambient > 20 && ambient < 48 * 48 - 200, "{ambient}");
    for out in [&again, &fresh] {
        assert_eq!(out.color.pixels, first.color.pixels);
        assert_eq!(out.depth.pixels, first.depth.pixels);
        assert_eq!(out.normal.pixels, first.normal.pixels);
        assert_eq!(out.position.pixels, first.position.pixels);
        assert_eq!(out.uv.pixels, first.uv.pixels);
        assert_eq!(out.base_color.pixels, first.base_color.pixels);
    }
}
