//! Path tracing speed and equal-time error on the Cornell box, beside Mitsuba 3.
//!
//! `cargo bench --bench trace` renders `assets/cornell/` (256x256, max_depth 8, box filter)
//! at several spp, reports wall time and millions of paths per second, and the RMSE (light
//! pixels masked as in the reference's SCENE.md: rows 28..=45, cols 101..=154) against a
//! high-spp reference rendered by cgnodes (cached in `target/trace_bench/`; the reference's
//! own noise, known from its variance image, is subtracted in quadrature). If
//! `bench/peers/trace_mitsuba.py` has been run first, its Mitsuba renders
//! (`target/trace_bench/mitsuba.json` + EXRs) are scored against the same reference, and a
//! chart of RMSE against time for both goes to `docs/path_tracing_rmse.svg`.
//!
//! Options (after `--`): `--ref-spp N` (default 2048), `--spp a,b,c` (default 4,16,64,256),
//! `--quick` (one 64-spp timing, no reference; `--quick-spp N` for another count),
//! `--grid-rays N` (camera rays per triangle from which `CameraGrid` is built, default 6),
//! `--binary-bvh` (traverse the binary BVH instead of the default one collapsed to 8 children per node, to measure what the wide
//! tree buys; `--wide-bvh`, the default, is accepted and does nothing), `--no-interleave`
//! (trace a path's shadow ray and its next ray one after the other instead of interleaved,
//! to measure what `Bvh::intersect_occluded` buys), `--scalar-paths` (one path at a time
//! instead of eight on lanes, `path_lanes`, to measure what the lanes buy),
//! `--bvh-camera-rays` (camera rays through the BVH instead of `CameraGrid`),
//! `--baseline-build` (no x86-64-v3 build of either loop, to measure what it buys), `--scene igea`
//! (the box with the 154k-triangle igea scan standing in it, white diffuse, as
//! `trace_mitsuba.py --scene igea` builds it; `--igea PATH`, default
//! `assets/meshes/igea_front.obj`), `--rays` (traversal alone, no shading:
//! path-like rays traced one at a time, in wavefront order and sorted by direction; see
//! `traversal_only`). The SVG chart is written for the plain box
//! only.

use cgnodes::nodes::mesh::obj::load_obj;
use cgnodes::nodes::trace::render_path::{render_opts, Filter, PathSettings, Shortcuts, Strategy};
use cgnodes::nodes::trace::render_scene::{PinholeCamera, RenderScene, SHADOW_END};
use cgnodes::nodes::trace::scene_load::load_obj_scene;
use cgnodes::types::{Camera, FovAxis, Image, Material, Scene, SceneObject};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

fn cpu_seconds() -> f64 {
    // utime + stime of this process, in clock ticks (field 14 and 15 of /proc/self/stat).
    let s = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let rest = s.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let t = |i: usize| f.get(i).and_then(|x| x.parse::<f64>().ok()).unwrap_or(0.0);
    (t(11) + t(12)) / 100.0
}

fn masked(x: u32, y: u32) -> bool {
    (28..=45).contains(&y) && (101..=154).contains(&x)
}

fn rmse(a: &Image, b: &Image) -> f64 {
    let mut s = 0.0;
    let mut n = 0.0;
    for y in 0..a.height {
        for x in 0..a.width {
            if masked(x, y) {
                continue;
            }
            let (p, q) = (a.get(x, y), b.get(x, y));
            for k in 0..3 {
                let d = p[k] as f64 - q[k] as f64;
                s += d * d;
                n += 1.0;
            }
        }
    }
    (s / n).sqrt()
}

fn mean_masked(v: &Image) -> f64 {
    let mut s = 0.0;
    let mut n = 0.0;
    for y in 0..v.height {
        for x in 0..v.width {
            if !masked(x, y) {
                let p = v.get(x, y);
                s += (p[0] + p[1] + p[2]) as f64;
                n += 3.0;
            }
        }
    }
    s / n
}

fn save_exr(img: &Image, p: &Path) {
    let buf: Vec<f32> = img.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
    let im = image::Rgb32FImage::from_raw(img.width, img.height, buf).unwrap();
    im.save(p).unwrap();
}

fn load_exr(p: &Path) -> Option<Image> {
    let im = image::open(p).ok()?.into_rgb32f();
    Some(Image {
        width: im.width(),
        height: im.height(),
        pixels: im.pixels().map(|q| [q[0], q[1], q[2], 1.0]).collect(),
    })
}

struct Row {
    who: String,
    spp: u32,
    /// Process CPU seconds (fair under a loaded machine), else wall seconds.
    secs: f64,
    rmse: Option<f64>,
}

fn svg_chart(rows: &[Row], path: &Path) {
    let pts: Vec<(&str, f64, f64)> = rows
        .iter()
        .filter_map(|r| r.rmse.map(|e| (r.who.as_str(), r.secs, e)))
        .filter(|p| p.1 > 0.0 && p.2 > 0.0)
        .collect();
    if pts.is_empty() {
        return;
    }
    let (w, h, m) = (640.0, 420.0, 60.0);
    let lx = |t: f64| t.log10();
    let (t0, t1) = pts.iter().fold((f64::MAX, f64::MIN), |a, p| {
        (a.0.min(lx(p.1)), a.1.max(lx(p.1)))
    });
    let (e0, e1) = pts.iter().fold((f64::MAX, f64::MIN), |a, p| {
        (a.0.min(lx(p.2)), a.1.max(lx(p.2)))
    });
    let (t0, t1, e0, e1) = (t0.floor(), t1.ceil(), e0.floor(), e1.ceil());
    let sx = |t: f64| m + (lx(t) - t0) / (t1 - t0) * (w - 2.0 * m);
    let sy = |e: f64| h - m - (lx(e) - e0) / (e1 - e0) * (h - 2.0 * m);
    let mut s = format!(
        "<svg xmlns='http://www.w3.org/2000/svg' width='{w}' height='{h}' font-family='sans-serif' font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n"
    );
    s += &format!("<text x='{}' y='20' text-anchor='middle'>Cornell box 256x256, max_depth 8, box filter: RMSE (light masked) vs process CPU seconds, log-log</text>\n", w / 2.0);
    for d in (t0 as i32)..=(t1 as i32) {
        let x = sx(10f64.powi(d));
        s += &format!("<line x1='{x}' y1='{}' x2='{x}' y2='{}' stroke='#ddd'/><text x='{x}' y='{}' text-anchor='middle'>1e{d} s CPU</text>\n", m, h - m, h - m + 16.0);
    }
    for d in (e0 as i32)..=(e1 as i32) {
        let y = sy(10f64.powi(d));
        s += &format!("<line x1='{m}' y1='{y}' x2='{}' y2='{y}' stroke='#ddd'/><text x='{}' y='{}' text-anchor='end'>1e{d}</text>\n", w - m, m - 4.0, y + 4.0);
    }
    let colors = ["#d62728", "#1f77b4", "#2ca02c", "#9467bd"];
    let mut names: Vec<&str> = pts.iter().map(|p| p.0).collect();
    names.dedup();
    for (i, name) in names.iter().enumerate() {
        let c = colors[i % colors.len()];
        let line: Vec<String> = pts
            .iter()
            .filter(|p| p.0 == *name)
            .map(|p| format!("{:.1},{:.1}", sx(p.1), sy(p.2)))
            .collect();
        s += &format!(
            "<polyline fill='none' stroke='{c}' stroke-width='2' points='{}'/>\n",
            line.join(" ")
        );
        for p in pts.iter().filter(|p| p.0 == *name) {
            s += &format!(
                "<circle cx='{:.1}' cy='{:.1}' r='3' fill='{c}'/>\n",
                sx(p.1),
                sy(p.2)
            );
        }
        s += &format!(
            "<text x='{}' y='{}' fill='{c}'>{name}</text>\n",
            w - m - 150.0,
            m + 16.0 * (i as f64 + 1.0)
        );
    }
    s += "</svg>\n";
    std::fs::write(path, s).unwrap();
}

/// Adds the igea scan to the box: scaled so its largest extent is 0.8, its box centre at
/// (0, -0.2, 0.2), white diffuse like the box's walls (`trace_mitsuba.py` applies the
/// same transform, computed from the same vertex bounds).
fn add_igea(scene: &mut Scene, path: &Path) {
    let mut mesh = load_obj(path, "").unwrap_or_else(|e| panic!("{e}"));
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for p in &mesh.positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let ext = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let s = 0.8 / ext;
    let at = [0.0, -0.2, 0.2];
    for p in &mut mesh.positions {
        for k in 0..3 {
            p[k] = (p[k] - 0.5 * (lo[k] + hi[k])) * s + at[k];
        }
    }
    mesh.normals = None;
    let white = Material {
        base_color: [0.885809, 0.698859, 0.666422],
        ..Default::default()
    };
    scene.objects.push(SceneObject {
        mesh: Arc::new(mesh),
        material: Some(Arc::new(white)),
    });
}

/// Traversal alone: rays as a path tracer meets them (camera rays, then three bounces of
/// cosine-sampled rays and shadow rays to the light from every hit), traced with
/// `intersect` and `occluded` on this thread (wall time, best of five), in the order a
/// wavefront would hold them (bounce by bounce, pixel order) and sorted by direction (the
/// same rays made coherent). Prints millions of rays per second.
fn traversal_only(sc: &RenderScene, cam: &PinholeCamera, dump: &Path) {
    use cgnodes::nodes::trace::bvh::Segment;
    use cgnodes::nodes::trace::sampling::{add, cosine_hemisphere, dot, scale, sub, Pcg32};
    let mut rng = Pcg32::new(5, 7);
    let mut level: Vec<Segment> = (0..256 * 256)
        .map(|p| {
            let (x, y) = ((p % 256) as f32 + 0.5, (p / 256) as f32 + 0.5);
            (cam.eye, cam.ray_dir(x, y), cam.far)
        })
        .collect();
    // Bounce by bounce, pixel order: the order a wavefront would hold them in.
    let (mut closest, mut shadow) = (Vec::new(), Vec::new());
    for _ in 0..3 {
        let mut next = Vec::new();
        for r in &level {
            let Some(h) = sc.bvh.intersect(r.0, r.1, r.2) else {
                continue;
            };
            let ng = sc.normal(h.prim);
            let side = if dot(ng, r.1) < 0.0 {
                ng
            } else {
                scale(ng, -1.0)
            };
            let o = sc.offset(add(r.0, scale(r.1, h.t)), side);
            next.push((o, cosine_hemisphere(side, rng.next_2d()), f32::INFINITY));
            if let Some(ls) = sc.sample_emitter(rng.next_f32(), rng.next_2d()) {
                shadow.push((o, sub(ls.p, o), SHADOW_END));
            }
        }
        closest.append(&mut level);
        level = next;
    }
    closest.append(&mut level);
    let (nc, ns) = (closest.len(), shadow.len());
    println!("{nc} closest-hit rays, {ns} shadow rays (camera and three bounces)");
    // For bench/peers/rays_mitsuba.py: the counts (u32), then per ray origin, direction and
    // tmax (7 f32), closest-hit rays first, little endian.
    let mut bytes = Vec::with_capacity(8 + 28 * (nc + ns));
    bytes.extend((nc as u32).to_le_bytes());
    bytes.extend((ns as u32).to_le_bytes());
    for r in closest.iter().chain(&shadow) {
        for x in r.0.iter().chain(&r.1).chain([&r.2]) {
            bytes.extend(x.to_le_bytes());
        }
    }
    std::fs::write(dump, bytes).unwrap();
    // Best wall time of five runs of both queries over all rays, and the hits found.
    let time = |cs: &[Segment], ss: &[Segment]| {
        let mut best = f64::INFINITY;
        let mut hits = 0;
        for _ in 0..5 {
            let c0 = Instant::now();
            hits = cs
                .iter()
                .filter(|r| sc.bvh.intersect(r.0, r.1, r.2).is_some())
                .count()
                + ss.iter().filter(|r| sc.bvh.occluded(r.0, r.1, r.2)).count();
            best = best.min(c0.elapsed().as_secs_f64());
        }
        (best, hits)
    };
    let (t1, h1) = time(&closest, &shadow);
    println!(
        "bounce by bounce, pixel order: {:.2} Mrays/s ({h1} hits)",
        (nc + ns) as f64 / t1 / 1e6
    );
    // The same rays sorted by direction (coherent): what incoherence costs.
    let key = |r: &Segment| {
        let q = |x: f32| ((x + 1.0) * 8.0) as u32;
        let (o, d) = (r.0, r.1);
        (q(d[0]), q(d[1]), q(d[2]), q(o[0] / 2.0), q(o[1] / 2.0))
    };
    closest.sort_by_key(key);
    shadow.sort_by_key(key);
    let (t2, h2) = time(&closest, &shadow);
    assert_eq!(h1, h2, "the sorted rays found other hits");
    println!(
        "sorted by direction: {:.2} Mrays/s, {:.2}x",
        (nc + ns) as f64 / t2 / 1e6,
        t1 / t2
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let get = |k: &str| {
        args.iter()
            .position(|a| a == k)
            .and_then(|i| args.get(i + 1).cloned())
    };
    let quick = args.iter().any(|a| a == "--quick");
    let ref_spp: u32 = get("--ref-spp")
        .and_then(|s| s.parse().ok())
        .unwrap_or(2048);
    let spps: Vec<u32> = get("--spp")
        .map(|s| s.split(',').filter_map(|x| x.parse().ok()).collect())
        .unwrap_or(vec![4, 16, 64, 256]);
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = root.join("target/trace_bench");
    std::fs::create_dir_all(&out).unwrap();
    let which = get("--scene").unwrap_or("box".into());
    let mut scene = load_obj_scene(&root.join("assets/cornell/cornell_box.obj"), false).unwrap();
    if which == "igea" {
        let p = get("--igea").unwrap_or("assets/meshes/igea_front.obj".into());
        add_igea(&mut scene, Path::new(&p));
    }
    let ntris: usize = scene
        .objects
        .iter()
        .map(|o| {
            o.mesh
                .face_counts()
                .iter()
                .map(|&c| (c as usize).saturating_sub(2))
                .sum::<usize>()
        })
        .sum();
    let cam = Camera {
        eye: [0.0, 0.0, 3.9],
        target: [0.0; 3],
        up: [0.0, 1.0, 0.0],
        fov_deg: 39.3077,
        fov_axis: FovAxis::Smaller,
        width: 256,
        height: 256,
        near: 0.001,
        far: 100.0,
    };
    let t = Instant::now();
    let mut sc = RenderScene::new(&scene).unwrap();
    if args.iter().any(|a| a == "--binary-bvh") {
        sc.bvh.narrow();
    }
    if args.iter().any(|a| a == "--no-interleave") {
        sc.bvh.one_at_a_time = true;
    }
    let cam = PinholeCamera::new(&cam).unwrap();
    println!(
        "scene {which} ({ntris} triangles) flatten + BVH: {:.3} ms",
        t.elapsed().as_secs_f64() * 1e3
    );
    let settings = |spp: u32, seed: u64| PathSettings {
        spp,
        max_depth: 8,
        rr_depth: 5,
        seed,
        filter: Filter::Box,
        strategy: Strategy::Mis,
        ..Default::default()
    };
    let threads = rayon::current_num_threads();
    let opts = Shortcuts {
        lanes: !args.iter().any(|a| a == "--scalar-paths"),
        camera_grid: !args.iter().any(|a| a == "--bvh-camera-rays"),
        x86_64_v3: !args.iter().any(|a| a == "--baseline-build"),
        grid_rays_per_triangle: get("--grid-rays")
            .and_then(|s| s.parse().ok())
            .unwrap_or(Shortcuts::default().grid_rays_per_triangle),
    };
    let run = |spp: u32, seed: u64| {
        let c0 = cpu_seconds();
        let t0 = Instant::now();
        let (img, var) = render_opts(&sc, &cam, &settings(spp, seed), &|_| {}, opts);
        let secs = t0.elapsed().as_secs_f64();
        let cpu = cpu_seconds() - c0;
        (img, var, secs, cpu)
    };
    if args.iter().any(|a| a == "--rays") {
        // (writes the rays to target/trace_bench/rays_<scene>.bin for the Mitsuba peer)
        traversal_only(&sc, &cam, &out.join(format!("rays_{which}.bin")));
        return;
    }
    if quick {
        let spp: u32 = get("--quick-spp")
            .and_then(|s| s.parse().ok())
            .unwrap_or(64);
        let (_, _, secs, cpu) = run(spp, 1);
        let paths = 256.0 * 256.0 * spp as f64;
        println!(
            "cgnodes {which} {spp} spp: {secs:.3} s wall, {cpu:.2} s CPU on {threads} threads: {:.2} Mpaths/s wall, {:.2} Mpaths per CPU-second",
            paths / secs / 1e6,
            paths / cpu.max(1e-9) / 1e6
        );
        return;
    }
    let ref_path: PathBuf = out.join(format!("ref_{which}_{ref_spp}.exr"));
    let ref_var_path: PathBuf = out.join(format!("ref_{which}_{ref_spp}_var.exr"));
    let (reference, ref_var) = match (load_exr(&ref_path), load_exr(&ref_var_path)) {
        (Some(r), Some(v)) => (r, v),
        _ => {
            println!("rendering the {ref_spp}-spp reference (cached afterwards)...");
            let (r, v, secs, _) = run(ref_spp, 987_654_321);
            println!("  {secs:.1} s");
            save_exr(&r, &ref_path);
            save_exr(&v, &ref_var_path);
            (r, v)
        }
    };
    // Mean squared noise of the reference itself, removed from every measured RMSE.
    let ref_noise2 = mean_masked(&ref_var);
    let corrected = |e: f64| (e * e - ref_noise2).max(0.0).sqrt();
    println!(
        "reference noise (rms, light masked): {:.5}",
        ref_noise2.sqrt()
    );
    let mut rows = Vec::new();
    for &spp in &spps {
        let (img, _, secs, cpu) = run(spp, 1);
        let paths = 256.0 * 256.0 * spp as f64;
        let e = corrected(rmse(&img, &reference));
        println!(
            "cgnodes {which} {spp:>5} spp: {secs:7.3} s wall ({cpu:.2} s CPU, {threads} threads), {:.2} Mpaths/s, {:.2} Mpaths per CPU-second, rmse_excl_light {e:.5}",
            paths / secs / 1e6,
            paths / cpu.max(1e-9) / 1e6
        );
        rows.push(Row {
            who: "cgnodes".into(),
            spp,
            secs: cpu,
            rmse: Some(e),
        });
    }
    let mj = out.join("mitsuba.json");
    if let Ok(text) = std::fs::read_to_string(&mj) {
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        for r in v["runs"].as_array().cloned().unwrap_or_default() {
            let variant = r["variant"].as_str().unwrap_or("?").to_string();
            if r["scene"].as_str().unwrap_or("box") != which {
                continue;
            }
            let spp = r["spp"].as_u64().unwrap_or(0) as u32;
            let secs = r["seconds"].as_f64().unwrap_or(0.0);
            let cpu = r["cpu_seconds"].as_f64().unwrap_or(f64::NAN);
            let img = r["exr"].as_str().and_then(|p| load_exr(&out.join(p)));
            let e = img.map(|i| corrected(rmse(&i, &reference)));
            println!(
                "mitsuba {variant} {which} {spp:>5} spp: {secs:7.3} s wall ({cpu:.2} s CPU), {:.2} Mpaths/s, {:.2} Mpaths per CPU-second, rmse_excl_light {}",
                256.0 * 256.0 * spp as f64 / secs / 1e6,
                256.0 * 256.0 * spp as f64 / cpu / 1e6,
                e.map_or("-".into(), |e| format!("{e:.5}"))
            );
            rows.push(Row {
                who: format!("mitsuba {variant}"),
                spp,
                secs: if cpu.is_finite() { cpu } else { secs },
                rmse: e,
            });
        }
    } else {
        println!("(no Mitsuba runs: run `python3 bench/peers/trace_mitsuba.py` first)");
    }
    let docs = root.join("docs");
    std::fs::create_dir_all(&docs).unwrap();
    if which == "box" {
        svg_chart(&rows, &docs.join("path_tracing_rmse.svg"));
    }
    // Equal-time comparison: interpolate each peer's RMSE at cgnodes' times (log-log).
    for r in rows.iter().filter(|r| r.who != "cgnodes") {
        if let Some(e) = r.rmse {
            let ours: Vec<&Row> = rows.iter().filter(|q| q.who == "cgnodes").collect();
            if let Some(w) = ours
                .windows(2)
                .find(|w| w[0].secs <= r.secs && r.secs <= w[1].secs)
            {
                let f = (r.secs.ln() - w[0].secs.ln()) / (w[1].secs.ln() - w[0].secs.ln());
                let eo = (w[0].rmse.unwrap().ln() * (1.0 - f) + w[1].rmse.unwrap().ln() * f).exp();
                println!(
                    "equal CPU time {:.3} s: {} spp {} rmse {e:.5}, cgnodes {eo:.5} (ratio {:.2})",
                    r.secs,
                    r.who,
                    r.spp,
                    e / eo
                );
            }
        }
    }
}
