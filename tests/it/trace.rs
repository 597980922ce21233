//! Path tracer checks against analytic results and against Mitsuba 3's Cornell box
//! (`tests/data/trace/ref_stats.json`, see `assets/cornell/README.md`).

use cgnodes::nodes::trace::render_path::{render_path, Filter, PathSettings, Strategy};
use cgnodes::nodes::trace::scene_load::load_obj_scene;
use cgnodes::types::{Camera, FovAxis, Image, Material, MaterialKind, Mesh, Scene, SceneObject};
use std::sync::Arc;

use crate::common::root;

/// A UV sphere; `inward` flips the winding so the normals face the centre.
pub(crate) fn sphere(c: [f64; 3], r: f64, n: usize, inward: bool) -> Mesh {
    let mut pos = vec![[c[0], c[1] + r, c[2]], [c[0], c[1] - r, c[2]]];
    let rings = n;
    let segs = 2 * n;
    for i in 1..rings {
        let th = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..segs {
            let ph = std::f64::consts::TAU * j as f64 / segs as f64;
            pos.push([
                c[0] + r * th.sin() * ph.cos(),
                c[1] + r * th.cos(),
                c[2] + r * th.sin() * ph.sin(),
            ]);
        }
    }
    let v = |i: usize, j: usize| (2 + (i - 1) * segs + j % segs) as u32;
    let mut tris = Vec::new();
    for j in 0..segs {
        tris.push([0, v(1, j + 1), v(1, j)]);
        tris.push([1, v(rings - 1, j), v(rings - 1, j + 1)]);
        for i in 1..rings - 1 {
            tris.push([v(i, j), v(i, j + 1), v(i + 1, j + 1)]);
            tris.push([v(i, j), v(i + 1, j + 1), v(i + 1, j)]);
        }
    }
    if inward {
        for t in &mut tris {
            t.swap(1, 2);
        }
    }
    Mesh::from_triangles(pos, &tris).unwrap()
}

fn camera(eye: [f64; 3], target: [f64; 3], fov: f64, w: u32, h: u32) -> Camera {
    Camera {
        eye,
        target,
        up: [0.0, 1.0, 0.0],
        fov_deg: fov,
        fov_axis: FovAxis::Smaller,
        width: w,
        height: h,
        near: 0.001,
        far: 100.0,
    }
}

fn mat(kind: MaterialKind, albedo: f64, emission: f64) -> Arc<Material> {
    Arc::new(Material {
        kind,
        base_color: [albedo; 3],
        emission: [emission; 3],
        two_sided_emission: true,
        ..Default::default()
    })
}

pub(crate) fn mean(img: &Image) -> [f64; 3] {
    let mut m = [0.0; 3];
    for p in &img.pixels {
        for k in 0..3 {
            m[k] += p[k] as f64;
        }
    }
    m.map(|x| x / img.pixels.len() as f64)
}

pub(crate) fn patch_mean(img: &Image, rows: [u32; 2], cols: [u32; 2]) -> [f64; 3] {
    let mut m = [0.0; 3];
    for y in rows[0]..rows[1] {
        for x in cols[0]..cols[1] {
            let p = img.get(x, y);
            for k in 0..3 {
                m[k] += p[k] as f64;
            }
        }
    }
    let n = ((rows[1] - rows[0]) * (cols[1] - cols[0])) as f64;
    m.map(|x| x / n)
}

fn settings(spp: u32, max_depth: u32, strategy: Strategy, filter: Filter) -> PathSettings {
    PathSettings {
        spp,
        max_depth,
        rr_depth: 5,
        seed: 1,
        filter,
        strategy,
        ..Default::default()
    }
}

fn noop(_: f64) {}

/// White furnace: a diffuse sphere of albedo 1 inside a black sphere emitting radiance 1
/// reflects exactly the radiance it receives, so every pixel reads 1 (for any strategy).
#[test]
fn white_furnace_returns_the_emission() {
    let scene = Scene {
        objects: vec![
            SceneObject {
                mesh: Arc::new(sphere([0.0; 3], 5.0, 24, true)),
                material: Some(mat(MaterialKind::Diffuse, 0.0, 1.0)),
            },
            SceneObject {
                mesh: Arc::new(sphere([0.0; 3], 1.0, 24, false)),
                material: Some(mat(MaterialKind::Diffuse, 1.0, 0.0)),
            },
        ],
        ..Default::default()
    };
    let cam = camera([0.0, 0.0, 3.0], [0.0; 3], 60.0, 32, 32);
    for strategy in [Strategy::Mis, Strategy::Nee, Strategy::Bsdf] {
        let (img, _) = render_path(
            &scene,
            Some(&cam),
            &settings(64, 16, strategy, Filter::Box),
            &noop,
        )
        .unwrap();
        let m = mean(&img);
        for k in 0..3 {
            assert!((m[k] - 1.0).abs() < 0.01, "{strategy:?}: mean {m:?}");
        }
        // The sphere's centre pixel (it fills the middle of the view).
        let c = patch_mean(&img, [10, 22], [10, 22]);
        assert!((c[0] - 1.0).abs() < 0.05, "{strategy:?}: centre {c:?}");
    }
}

/// Inside a closed sphere of albedo a emitting L_e, a path of at most D segments collects
/// L_e (1 + a + ... + a^(D-1)) = L_e (1 - a^D) / (1 - a): checks Mitsuba's max_depth
/// meaning and that Russian roulette keeps the unbounded sum L_e / (1 - a).
#[test]
fn albedo_below_one_loses_energy_as_the_geometric_series() {
    let a = 0.6;
    let scene = Scene {
        objects: vec![SceneObject {
            mesh: Arc::new(sphere([0.0; 3], 2.0, 16, true)),
            material: Some(mat(MaterialKind::Diffuse, a, 1.0)),
        }],
        ..Default::default()
    };
    let cam = camera([0.3, -0.2, 0.5], [0.0, 0.0, -1.0], 60.0, 24, 24);
    for (depth, spp) in [(1u32, 4u32), (2, 64), (3, 64), (8, 128), (u32::MAX, 256)] {
        let (img, _) = render_path(
            &scene,
            Some(&cam),
            &settings(spp, depth, Strategy::Mis, Filter::Box),
            &noop,
        )
        .unwrap();
        let want = if depth == u32::MAX {
            1.0 / (1.0 - a)
        } else {
            (1.0 - a.powi(depth as i32)) / (1.0 - a)
        };
        let m = mean(&img)[1];
        assert!(
            (m - want).abs() < 0.01 * want,
            "max_depth {depth}: mean {m}, want {want}"
        );
    }
}

fn cornell_scene() -> Scene {
    load_obj_scene(&root().join("assets/cornell/cornell_box.obj"), false).unwrap()
}

fn cornell_camera(w: u32, h: u32) -> Camera {
    camera([0.0, 0.0, 3.9], [0.0; 3], 39.3077, w, h)
}

/// Tracing a path's shadow ray beside its next segment (the two traversals interleaved)
/// changes no bit of the image: the Cornell box with two glossy conductors, a point light
/// (delta lights are estimated between the deferred shadow ray and the next hit) and the
/// Gaussian filter, against the same render with the rays traced one at a time.
#[test]
fn interleaved_shadow_rays_change_no_bit() {
    use cgnodes::nodes::trace::render_path::render;
    use cgnodes::nodes::trace::render_scene::prepare;
    let mut scene = cornell_scene();
    for o in scene.objects.iter_mut().take(2) {
        let mut m = (**o.material.as_ref().unwrap()).clone();
        m.kind = MaterialKind::Conductor { roughness: 0.3 };
        o.material = Some(Arc::new(m));
    }
    scene.lights.push(cgnodes::types::Light::Point {
        position: [0.3, 0.5, 0.5],
        color: [1.0, 0.9, 0.8],
        intensity: 2.0,
    });
    let cam = cornell_camera(24, 24);
    let (mut sc, pc) = prepare(&scene, Some(&cam), 0.0).unwrap();
    let s = settings(5, 8, Strategy::Mis, Filter::Gaussian);
    let (pairs, pairs_var) = render(&sc, &pc, &s, &noop);
    sc.bvh.one_at_a_time = true;
    let (single, single_var) = render(&sc, &pc, &s, &noop);
    let bits = |i: &Image| {
        i.pixels
            .iter()
            .flat_map(|p| p.map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    assert!(mean(&single)[0] > 0.01, "the render is black");
    assert_eq!(bits(&pairs), bits(&single), "shadow rays interleaved");
    assert_eq!(bits(&pairs_var), bits(&single_var));
}

/// The four-lane loop (`path_lanes`) renders exactly the scalar loop's image, bit for bit:
/// the Cornell box as shipped (flat, diffuse); with a smooth-shaded sphere (corner normals
/// interpolated) and a two-sided emitter inside it; and with a textured quad, a point and
/// a directional light and the HDR sky of `assets/envmaps/sky.exr` through the open front.
/// Under both filters, all three strategies, at spp and sizes that leave lanes idle at the
/// ends of batches, with Russian roulette from the first bounce, a short depth limit and
/// none. Camera rays through the BVH instead of the per-pixel candidates of `CameraGrid`
/// change no bit either.
#[test]
fn lane_paths_change_no_bit() {
    use cgnodes::nodes::trace::path_lanes::handles;
    use cgnodes::nodes::trace::render_path::{render_opts, Shortcuts};
    use cgnodes::nodes::trace::render_scene::prepare;
    let bits = |i: &Image| {
        i.pixels
            .iter()
            .flat_map(|p| p.map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    let plain = cornell_scene();
    let mut smooth = cornell_scene();
    smooth.objects.push(SceneObject {
        mesh: Arc::new(sphere([-0.3, -0.2, 0.3], 0.3, 10, false)),
        material: Some(mat(MaterialKind::Diffuse, 0.7, 0.0)),
    });
    smooth.objects.push(SceneObject {
        mesh: Arc::new(sphere([0.4, 0.3, 0.2], 0.08, 6, false)),
        material: Some(mat(MaterialKind::Diffuse, 0.5, 3.0)),
    });
    let mut lit = smooth.clone();
    let mut quad = crate::trace_shading::uv_quad();
    for p in &mut quad.positions {
        *p = [0.3 * p[0] + 0.3, 0.3 * p[1] + 0.2, -0.6];
    }
    let mut tex = Image::new(4, 4, [0.0, 0.0, 0.0, 1.0]);
    for (k, px) in tex.pixels.iter_mut().enumerate() {
        *px = [0.2 + 0.05 * k as f32, 0.9 - 0.05 * k as f32, 0.5, 1.0];
    }
    lit.objects.push(SceneObject {
        mesh: Arc::new(quad),
        material: Some(Arc::new(Material {
            base_color: [0.9, 0.8, 1.0],
            base_color_texture: Some(Arc::new(tex)),
            ..Default::default()
        })),
    });
    let bytes = std::fs::read(root().join("assets/envmaps/sky.exr")).unwrap();
    let sky = cgnodes::nodes::image::image_load::decode_image(
        &bytes,
        cgnodes::nodes::image::image_load::ColorSpace::Raw,
    )
    .unwrap();
    lit.lights = vec![
        cgnodes::types::Light::Point {
            position: [-0.4, 0.6, 0.4],
            color: [1.0, 0.9, 0.8],
            intensity: 1.5,
        },
        cgnodes::types::Light::Directional {
            direction: [0.2, -0.3, -1.0],
            color: [0.8, 0.9, 1.0],
            intensity: 2.0,
        },
        cgnodes::types::Light::Environment {
            image: Some(Arc::new(sky)),
            color: [1.0; 3],
            intensity: 0.5,
            rotation_deg: 30.0,
        },
    ];
    let mis = Strategy::Mis;
    let cases = [
        (&plain, mis, 5, 8, 5, Filter::Box, 19),
        (&plain, mis, 3, u32::MAX, 1, Filter::Gaussian, 21),
        (&smooth, mis, 7, 8, 2, Filter::Gaussian, 17),
        (&smooth, mis, 2, 3, 1, Filter::Box, 18),
        (&lit, mis, 3, 8, 2, Filter::Gaussian, 20),
        (&lit, Strategy::Nee, 3, 8, 1, Filter::Box, 17),
        (&lit, Strategy::Bsdf, 3, u32::MAX, 3, Filter::Gaussian, 18),
        (&plain, Strategy::Nee, 2, 8, 5, Filter::Box, 16),
    ];
    for (scene, strategy, spp, max_depth, rr_depth, filter, size) in cases {
        let cam = cornell_camera(size, size);
        let (sc, pc) = prepare(scene, Some(&cam), 60.0).unwrap();
        let s = PathSettings {
            rr_depth,
            ..settings(spp, max_depth, strategy, filter)
        };
        assert!(handles(&sc), "the lane loop takes this scene");
        // The grid is built however few the camera rays, so that it is compared below.
        // The one-path loop in the baseline build against the lanes in the x86-64-v3 one
        // (where the CPU has it).
        let lanes_on = |lanes| Shortcuts {
            lanes,
            grid_rays_per_triangle: 0,
            x86_64_v3: lanes,
            ..Default::default()
        };
        let (lanes, lanes_var) = render_opts(&sc, &pc, &s, &noop, lanes_on(true));
        let (scalar, scalar_var) = render_opts(&sc, &pc, &s, &noop, lanes_on(false));
        assert!(mean(&scalar)[0] > 0.01, "the render is black");
        let what = format!("{strategy:?}, spp {spp}, max_depth {max_depth}");
        assert_eq!(bits(&lanes), bits(&scalar), "{what}");
        assert_eq!(bits(&lanes_var), bits(&scalar_var), "{what}");
        // Camera rays through the BVH instead of `CameraGrid`: the same hits.
        let bvh_rays = Shortcuts {
            camera_grid: false,
            ..Default::default()
        };
        let (plain, _) = render_opts(&sc, &pc, &s, &noop, bvh_rays);
        assert_eq!(
            bits(&plain),
            bits(&lanes),
            "{what}, camera rays through the BVH"
        );
    }
    // What it does not take: a glossy material.
    let cam = cornell_camera(8, 8);
    let mut glossy = cornell_scene();
    let mut m = (**glossy.objects[0].material.as_ref().unwrap()).clone();
    m.kind = MaterialKind::Conductor { roughness: 0.3 };
    glossy.objects[0].material = Some(Arc::new(m));
    let (sc, pc) = prepare(&glossy, Some(&cam), 60.0).unwrap();
    assert!(!handles(&sc));
    // Its one-path loop gives the same bits in both builds (the x86-64-v3 one where the
    // CPU has it).
    let s = settings(8, 8, Strategy::Mis, Filter::Box);
    let build = |x86_64_v3| Shortcuts {
        x86_64_v3,
        ..Default::default()
    };
    let (v3, v3_var) = render_opts(&sc, &pc, &s, &noop, build(true));
    let (base, base_var) = render_opts(&sc, &pc, &s, &noop, build(false));
    assert!(mean(&base)[0] > 0.01, "the glossy render is black");
    assert_eq!(bits(&v3), bits(&base));
    assert_eq!(bits(&v3_var), bits(&base_var));
}

/// Emitter sampling alone, BSDF sampling alone and their MIS combination estimate the same
/// image: the Cornell box at low resolution, with the short box turned into a rough GGX
/// conductor so a glossy lobe is exercised too.
#[test]
fn nee_bsdf_and_mis_agree_in_expectation() {
    let mut scene = cornell_scene();
    let mut glossy = 0;
    for o in &mut scene.objects {
        let m = o.mesh.bounds();
        // The short box ("small-box" in the OBJ): its faces all lie within -1 <= y <= -0.4
        // and x >= -0.04; the floor and the tall box reach further.
        if m.1[1] <= -0.39 && m.0[0] > -0.05 && m.1[1] > -0.9 {
            assert_eq!(o.mesh.num_faces(), 12, "the short box has 12 triangles");
            let mut mm = (**o.material.as_ref().unwrap()).clone();
            mm.kind = MaterialKind::Conductor { roughness: 0.5 };
            mm.base_color = [0.9, 0.7, 0.4];
            o.material = Some(Arc::new(mm));
            glossy += 1;
        }
    }
    // Without the glossy box the comparison would run on an all-diffuse scene.
    assert_eq!(
        glossy, 1,
        "the short box was not found in the Cornell scene"
    );
    let conductors = scene
        .objects
        .iter()
        .filter(|o| {
            o.material.as_ref().is_some_and(
                |m| matches!(m.kind, MaterialKind::Conductor { roughness } if roughness == 0.5),
            )
        })
        .count();
    assert_eq!(conductors, 1);
    let cam = cornell_camera(32, 32);
    let mut means = Vec::new();
    for (strategy, spp) in [
        (Strategy::Mis, 256),
        (Strategy::Nee, 256),
        (Strategy::Bsdf, 1024),
    ] {
        let (img, _) = render_path(
            &scene,
            Some(&cam),
            &settings(spp, 8, strategy, Filter::Box),
            &noop,
        )
        .unwrap();
        // Whole image and the lower half (floor, boxes) without the light's pixels.
        means.push((strategy, mean(&img), patch_mean(&img, [16, 32], [0, 32])));
    }
    let (_, m0, p0) = means[0];
    for (s, m, p) in &means[1..] {
        for k in 0..3 {
            assert!(
                (m[k] - m0[k]).abs() < 0.02 * m0[k],
                "{s:?} whole-image mean {m:?} vs MIS {m0:?}"
            );
            assert!(
                (p[k] - p0[k]).abs() < 0.03 * p0[k],
                "{s:?} lower-half mean {p:?} vs MIS {p0:?}"
            );
        }
    }
}

fn ref_stats() -> serde_json::Value {
    let s = std::fs::read_to_string(root().join("tests/data/trace/ref_stats.json")).unwrap();
    serde_json::from_str(&s).unwrap()
}

fn triple(v: &serde_json::Value) -> [f64; 3] {
    let a = v.as_array().unwrap();
    [
        a[0].as_f64().unwrap(),
        a[1].as_f64().unwrap(),
        a[2].as_f64().unwrap(),
    ]
}

fn check_cornell(filter: Filter, key: &str, mean_key: &str) {
    let (img, var) = render_path(
        &cornell_scene(),
        Some(&cornell_camera(256, 256)),
        &settings(64, 8, Strategy::Mis, filter),
        &noop,
    )
    .unwrap();
    assert_eq!((img.width, img.height), (256, 256));
    let r = ref_stats();
    let m = mean(&img);
    let want = triple(&r["image_mean_rgb"][mean_key]);
    for k in 0..3 {
        assert!(
            (m[k] - want[k]).abs() < 0.01 * want[k],
            "{key}: image mean {m:?} vs Mitsuba {want:?}"
        );
    }
    let patches = r["patches_rows_cols_halfopen"].as_object().unwrap();
    assert_eq!(patches.len(), 8, "the reference's patches");
    for (name, p) in patches {
        let rows = triple(&serde_json::json!([p["rows"][0], p["rows"][1], 0]));
        let cols = triple(&serde_json::json!([p["cols"][0], p["cols"][1], 0]));
        let got = patch_mean(
            &img,
            [rows[0] as u32, rows[1] as u32],
            [cols[0] as u32, cols[1] as u32],
        );
        let want = triple(&p[key]);
        for k in 0..3 {
            assert!(
                (got[k] - want[k]).abs() < 0.03 * want[k],
                "{key}: patch {name} {got:?} vs Mitsuba {want:?}"
            );
        }
    }
    // The variance image is the sample variance over spp: away from the light it must be
    // of the size the reference's noise figures imply (rmse ~0.09 / sqrt(spp) box).
    let v = patch_mean(&var, [60, 80], [140, 180]);
    assert!(v[0] > 0.0 && v[0].sqrt() < 0.1, "variance {v:?}");
}

/// At 64 spp the box-filtered Cornell box matches Mitsuba's 8192-spp box reference.
#[test]
fn cornell_box_filter_matches_mitsuba() {
    check_cornell(Filter::Box, "box", "box_8192spp");
}

/// At 64 spp the Gaussian-filtered Cornell box matches Mitsuba's 16384-spp reference.
#[test]
fn cornell_gaussian_filter_matches_mitsuba() {
    check_cornell(Filter::Gaussian, "gaussian", "gaussian_16384spp");
}
