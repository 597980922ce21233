//! Benchmark: Tutte's embedding (uniform and cotangent weights, circle boundary) beside libigl
//! on the same meshes in the same run, and agreement of the UVs after a similarity.
//!
//! Run: `cargo bench --bench param` (default meshes: nefertiti_front and igea_front from
//! assets/meshes), or `cargo bench --bench param -- A.obj B.obj`. The libigl side
//! is `bench/peers/param_libigl.py` (`pip install libigl`); without it only our times print.
//! Our time includes building the mesh connectivity (the mesh is rebuilt before every run).

use cgnodes::nodes::mesh::mesh_load::{load_mesh, LoadOptions};
use cgnodes::nodes::param::triangles::fan_triangles;
use cgnodes::nodes::param::tutte::{tutte, TutteOptions, TutteWeights};
use cgnodes::nodes::param::uv_metrics::uv_metrics;
use cgnodes::types::Mesh;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn write_f64(path: &Path, vals: impl Iterator<Item = f64>) {
    let bytes: Vec<u8> = vals.flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(path, bytes).unwrap();
}

fn main() {
    let mut meshes: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    if meshes.is_empty() {
        meshes = ["nefertiti_front.obj", "igea_front.obj"]
            .iter()
            .map(|m| format!("assets/meshes/{m}"))
            .collect();
    }
    let dir = tempfile::tempdir().unwrap();
    let mut entries = Vec::new();
    println!("| mesh (faces) | weights | cgnodes ms (median) | flips | ARAP E |");
    println!("|---|---|---|---|---|");
    for path in &meshes {
        let m = load_mesh(Path::new(path), &LoadOptions::default()).unwrap();
        let name = Path::new(path)
            .file_stem()
            .unwrap()
            .to_string_lossy()
            .to_string();
        let tris = fan_triangles(&m);
        let reps = if tris.len() > 100_000 { 5 } else { 15 };
        let vpath = dir.path().join(format!("{name}_V.bin"));
        let fpath = dir.path().join(format!("{name}_F.bin"));
        write_f64(&vpath, m.positions.iter().flatten().copied());
        let fbytes: Vec<u8> = tris
            .iter()
            .flatten()
            .flat_map(|&v| (v as i64).to_le_bytes())
            .collect();
        std::fs::write(&fpath, fbytes).unwrap();
        let mut ours = Vec::new();
        for (w, wname) in [
            (TutteWeights::Uniform, "uniform"),
            (TutteWeights::Cotangent, "cotangent"),
            (TutteWeights::MeanValue, "mean_value"),
        ] {
            let opts = TutteOptions {
                weights: w,
                ..Default::default()
            };
            let mut times = Vec::new();
            let mut uv = Vec::new();
            for _ in 0..reps + 1 {
                let fresh = Mesh::from_triangles(m.positions.clone(), &tris).unwrap();
                let t0 = Instant::now();
                uv = tutte(&fresh, &opts).unwrap().uvs;
                times.push(t0.elapsed().as_secs_f64() * 1e3);
            }
            times.remove(0); // warm-up
            times.sort_by(f64::total_cmp);
            let ms = times[times.len() / 2];
            let met = uv_metrics(&m.positions, &tris, &uv);
            println!(
                "| {name} ({}) | {wname} | {ms:.1} | {} | {:.3} |",
                tris.len(),
                met.flipped,
                met.arap_energy
            );
            let uvpath = dir.path().join(format!("{name}_{wname}_uv.bin"));
            write_f64(&uvpath, uv.iter().flatten().copied());
            ours.push(format!(
                "\"{wname}\": {{\"ms\": {ms}, \"uv\": \"{}\"}}",
                uvpath.display()
            ));
        }
        entries.push(format!(
            "{{\"name\": \"{name}\", \"reps\": {reps}, \"V\": \"{}\", \"F\": \"{}\", \"ours\": {{{}}}}}",
            vpath.display(),
            fpath.display(),
            ours.join(", ")
        ));
    }
    let manifest: PathBuf = dir.path().join("manifest.json");
    let mut f = std::fs::File::create(&manifest).unwrap();
    write!(f, "{{\"meshes\": [{}]}}", entries.join(", ")).unwrap();
    drop(f);
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("bench/peers/param_libigl.py");
    println!();
    match std::process::Command::new("python3")
        .arg(&script)
        .arg(&manifest)
        .status()
    {
        Ok(s) if s.success() => {}
        Ok(s) => {
            eprintln!("libigl comparison failed ({s}); is libigl installed (pip install libigl)?")
        }
        Err(e) => eprintln!("could not run python3: {e}"),
    }
}
