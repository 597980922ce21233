//! Loading `igea_front.obj` (154k faces): cgnodes' `mesh_load` path (tobj, vertex welding
//! across groups, mesh checks) plus building the shared connectivity, beside tobj alone with
//! the same options. Run: `cargo bench --bench mesh_load` (reads assets/meshes/igea_front.obj, or the path
//! given as the first argument).

use cgnodes::nodes::mesh::mesh_load::{load_mesh, LoadOptions};
use std::path::PathBuf;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let path = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("assets/meshes/igea_front.obj"));
    if !path.exists() {
        eprintln!("skipping: {} not found", path.display());
        return;
    }
    let runs = 5;
    let mut t_tobj = Vec::new();
    let mut t_load = Vec::new();
    let mut t_topo = Vec::new();
    let (mut nv, mut nf) = (0, 0);
    for _ in 0..runs {
        let t = Instant::now();
        let opts = tobj::LoadOptions {
            triangulate: false,
            single_index: false,
            ..Default::default()
        };
        let (models, _) = tobj::load_obj(&path, &opts).expect("tobj");
        std::hint::black_box(&models);
        t_tobj.push(t.elapsed().as_secs_f64() * 1e3);

        let t = Instant::now();
        let m = load_mesh(
            &path,
            &LoadOptions {
                apply_transform: true,
                ..Default::default()
            },
        )
        .expect("load");
        t_load.push(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        let topo = m.topology();
        std::hint::black_box(topo.boundary_loops.len());
        t_topo.push(t.elapsed().as_secs_f64() * 1e3);
        (nv, nf) = (m.num_vertices(), m.num_faces());
    }
    let (a, b, c) = (median(t_tobj), median(t_load), median(t_topo));
    println!(
        "mesh_load benchmark: {} ({nv} vertices, {nf} faces), median of {runs}",
        path.display()
    );
    println!("  tobj alone                 {a:8.1} ms");
    println!(
        "  cgnodes load_mesh          {b:8.1} ms   ({:.2}x tobj)",
        b / a
    );
    println!("  + connectivity (topology)  {c:8.1} ms");
    println!(
        "  load + connectivity        {:8.1} ms   ({:.2}x tobj)",
        b + c,
        (b + c) / a
    );
}
