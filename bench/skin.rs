//! Skinning benchmark: LBS and DQS milliseconds per frame on a 100k-vertex tube with four
//! influences per vertex over an eight-joint chain (animated rotations), beside usd-core's
//! `UsdSkel.SkinPointsLBS` on the same points, weights and joint transforms in the same run
//! (`bench/peers/skin_usd.py`, which also checks that both give the same points).
//!
//! `cargo bench --bench skin` (`SKIN_VERTICES`, default 100000; `SKIN_FRAMES`, default 8;
//! `SKIN_REPEAT`, default 5; `SKIN_SKIP_PEER=1` skips usd-core). Times are medians over
//! frames and repeats of the plain functions `lbs_points` and `dqs` (points only; normals
//! are not timed), after the pose (`skinning_transforms`), with rayon's default threads.

use cgnodes::nodes::anim::dqs::dqs;
use cgnodes::nodes::anim::lbs::{check_influences, joint_matrices, lbs_points, Influences};
use cgnodes::nodes::anim::pose::skinning_transforms;
use cgnodes::nodes::mesh::usda::transform::Mat4;
use cgnodes::types::{Joint, SkelAnimation, Skeleton, Track, IDENTITY_MATRIX};
use std::io::Write;
use std::time::Instant;

const JOINTS: usize = 8;

fn env(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// A tube of `n` vertices along z (length 8, radius 0.5) with four influences per vertex:
/// the two nearest joints and their neighbours, Gaussian weights normalized.
fn tube(n: usize) -> (Vec<[f64; 3]>, Vec<u32>, Vec<f64>) {
    let seg = 100;
    let rings = n / seg;
    let mut p = Vec::with_capacity(n);
    let mut idx = Vec::with_capacity(4 * n);
    let mut w = Vec::with_capacity(4 * n);
    for r in 0..rings {
        let z = 8.0 * r as f64 / (rings - 1) as f64;
        for s in 0..seg {
            let a = std::f64::consts::TAU * s as f64 / seg as f64;
            p.push([0.5 * a.cos(), 0.5 * a.sin(), z]);
            let near = (z.round() as usize).min(JOINTS - 1);
            let first = near.saturating_sub(1).min(JOINTS - 4);
            let raw: Vec<f64> = (first..first + 4)
                .map(|j| (-((z - j as f64) / 0.8).powi(2)).exp())
                .collect();
            let sum: f64 = raw.iter().sum();
            for (k, j) in (first..first + 4).enumerate() {
                // Reverse the order on odd vertices so that index order is not sorted.
                let jj = if p.len() % 2 == 1 { first + 3 - k } else { j };
                idx.push(jj as u32);
                w.push(raw[jj - first] / sum);
            }
        }
    }
    (p, idx, w)
}

fn skeleton(frames: usize) -> Skeleton {
    let mut joints = Vec::new();
    for j in 0..JOINTS {
        let mut bind = IDENTITY_MATRIX;
        bind[3][2] = j as f64;
        let mut rest = IDENTITY_MATRIX;
        rest[3][2] = if j == 0 { 0.0 } else { 1.0 };
        joints.push(Joint {
            path: (0..=j)
                .map(|i| format!("J{i}"))
                .collect::<Vec<_>>()
                .join("/"),
            parent: j.checked_sub(1),
            bind,
            rest,
        });
    }
    let times: Vec<f64> = (0..frames).map(|f| f as f64).collect();
    let rotations = times
        .iter()
        .map(|&t| {
            (0..JOINTS)
                .map(|j| {
                    let h = 0.5 * (0.2 + 0.05 * t) * ((j % 3) as f64 - 1.0 + 0.3);
                    let axis = [(j as f64).cos(), (j as f64).sin(), 0.3];
                    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
                    [
                        h.cos(),
                        h.sin() * axis[0] / n,
                        h.sin() * axis[1] / n,
                        h.sin() * axis[2] / n,
                    ]
                })
                .collect()
        })
        .collect();
    let translations = Track {
        times: vec![],
        values: vec![(0..JOINTS)
            .map(|j| [0.0, 0.0, if j == 0 { 0.0 } else { 1.0 }])
            .collect()],
    };
    Skeleton {
        prim: "/Bench/Skel".into(),
        joints,
        animation: Some(SkelAnimation {
            prim: "/Bench/Anim".into(),
            joints: (0..JOINTS).collect(),
            translations,
            rotations: Track {
                times,
                values: rotations,
            },
            scales: None,
        }),
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn write_f64(path: &std::path::Path, v: impl Iterator<Item = f64>) {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    for x in v {
        f.write_all(&x.to_le_bytes()).unwrap();
    }
}

fn main() {
    let n = env("SKIN_VERTICES", 100_000);
    let frames = env("SKIN_FRAMES", 8);
    let repeat = env("SKIN_REPEAT", 5);
    let (points, idx, w) = tube(n);
    let n = points.len();
    let skel = skeleton(frames);
    let inf = Influences {
        count: 4,
        indices: &idx,
        weights: &w,
    };
    check_influences(&inf, n, JOINTS).unwrap();
    let id = Mat4::identity();
    let (mut t_lbs, mut t_dqs) = (Vec::new(), Vec::new());
    let mut ours = Vec::new();
    let mut xforms = Vec::new();
    for f in 0..frames {
        let xf = skinning_transforms(&skel, f as f64).unwrap();
        let m = joint_matrices(&id, &xf, &id);
        for r in 0..repeat {
            let t0 = Instant::now();
            let p = lbs_points(&points, &inf, &m);
            t_lbs.push(t0.elapsed().as_secs_f64() * 1e3);
            let t0 = Instant::now();
            let d = dqs(&points, None, &inf, &id, &xf, &id);
            t_dqs.push(t0.elapsed().as_secs_f64() * 1e3);
            std::hint::black_box(&d);
            if r == 0 {
                ours.push(p);
            }
        }
        xforms.push(xf);
    }
    let (lbs_ms, dqs_ms) = (median(t_lbs), median(t_dqs));
    println!("skin: {n} vertices, 4 influences, {JOINTS} joints, {frames} frames x {repeat} repeats, {} rayon threads", rayon::current_num_threads());
    println!("cgnodes LBS: {lbs_ms:.2} ms/frame (target <= 5)");
    println!("cgnodes DQS: {dqs_ms:.2} ms/frame (target <= 10)");
    if std::env::var("SKIN_SKIP_PEER").is_ok_and(|v| v == "1") {
        return;
    }
    let dir = std::env::temp_dir().join(format!("cgnodes-skin-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    write_f64(&dir.join("points.f64"), points.iter().flatten().copied());
    write_f64(&dir.join("weights.f64"), w.iter().copied());
    let mut f = std::fs::File::create(dir.join("indices.i32")).unwrap();
    for &j in &idx {
        f.write_all(&(j as i32).to_le_bytes()).unwrap();
    }
    write_f64(
        &dir.join("xforms.f64"),
        xforms
            .iter()
            .flatten()
            .flat_map(|m| (0..16).map(move |e| m[(e / 4, e % 4)])),
    );
    write_f64(
        &dir.join("ours.f64"),
        ours.iter().flatten().flatten().copied(),
    );
    let meta = format!("{{\"vertices\": {n}, \"influences\": 4, \"joints\": {JOINTS}, \"frames\": {frames}, \"repeat\": {repeat}}}");
    std::fs::write(dir.join("meta.json"), meta).unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::process::Command::new("python3")
        .arg(root.join("bench/peers/skin_usd.py"))
        .arg(&dir)
        .output();
    let _ = std::fs::remove_dir_all(&dir);
    let line = out.ok().and_then(|o| {
        if !o.status.success() {
            eprintln!("{}", String::from_utf8_lossy(&o.stderr));
        }
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .find(|l| l.starts_with('{'))
            .map(str::to_string)
    });
    match line.and_then(|l| serde_json::from_str::<serde_json::Value>(&l).ok()) {
        Some(j) => {
            let peer = j["ms_per_frame"].as_f64().unwrap_or(f64::NAN);
            println!("usd-core SkinPointsLBS: {peer:.2} ms/frame (same points; largest difference {:.1e} of the bbox diagonal)", j["max_rel_diff"].as_f64().unwrap_or(f64::NAN));
            println!(
                "ratio cgnodes/usd-core: LBS {:.2}, DQS {:.2}",
                lbs_ms / peer,
                dqs_ms / peer
            );
        }
        None => println!("usd-core peer did not run (python3 bench/peers/skin_usd.py)"),
    }
}
