//! `mesh_info`: counts and topology facts of a mesh as a one-row table (vertices, faces,
//! edges, bounding box, boundary loops and their lengths, components, Euler characteristic,
//! genus, manifoldness, degenerate faces).

use cgnodes_api::prelude::*;

/// Area of a polygon by Newell's method (half the length of the summed cross products),
/// valid for non-planar polygons too.
pub fn polygon_area(mesh: &Mesh, face: &[u32]) -> f64 {
    let mut n = [0.0; 3];
    for k in 0..face.len() {
        let a = mesh.positions[face[k] as usize];
        let b = mesh.positions[face[(k + 1) % face.len()] as usize];
        n[0] += (a[1] - b[1]) * (a[2] + b[2]);
        n[1] += (a[2] - b[2]) * (a[0] + b[0]);
        n[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The signed volume enclosed by a closed, outward-oriented mesh (divergence theorem over a
/// fan triangulation of each face: `V = Σ p0 · (p1 × p2) / 6`); meaningless for an open mesh.
pub fn signed_volume(mesh: &Mesh) -> f64 {
    use cgnodes_api::types::vec3::{cross, dot};
    mesh.faces()
        .map(|f| {
            let p0 = mesh.positions[f[0] as usize];
            (1..f.len() - 1)
                .map(|k| {
                    let p1 = mesh.positions[f[k] as usize];
                    let p2 = mesh.positions[f[k + 1] as usize];
                    dot(p0, cross(p1, p2))
                })
                .sum::<f64>()
        })
        .sum::<f64>()
        / 6.0
}

/// The facts `mesh_info` reports, as a one-row table. Loop sizes and lengths go into `meta`
/// (`boundary_loop_sizes`, `boundary_loop_lengths`), as does `manifold_problems` when the
/// mesh is not manifold. `genus` is -1 when undefined (non-manifold or several components).
pub fn mesh_info(mesh: &Mesh) -> Table {
    let t = mesh.topology();
    let (lo, hi) = mesh.bounds();
    let diag = dist(lo, hi);
    let area_eps = 1e-14 * diag * diag;
    let areas: Vec<f64> = mesh.faces().map(|f| polygon_area(mesh, f)).collect();
    let degenerate = areas.iter().filter(|&&a| a <= area_eps).count();
    let loop_len: Vec<f64> = t
        .boundary_loops
        .iter()
        .map(|l| {
            (0..l.len())
                .map(|k| {
                    dist(
                        mesh.positions[l[k] as usize],
                        mesh.positions[l[(k + 1) % l.len()] as usize],
                    )
                })
                .sum()
        })
        .collect();
    let bool_f = |b: bool| if b { 1.0 } else { 0.0 };
    let mut table = Table::from_row(&[
        ("vertices", mesh.num_vertices() as f64),
        ("faces", mesh.num_faces() as f64),
        ("edges", t.num_edges() as f64),
        ("corners", mesh.face_indices().len() as f64),
        ("triangles_only", bool_f(mesh.is_triangle_mesh())),
        ("min_x", lo[0]),
        ("min_y", lo[1]),
        ("min_z", lo[2]),
        ("max_x", hi[0]),
        ("max_y", hi[1]),
        ("max_z", hi[2]),
        ("area", areas.iter().sum()),
        ("boundary_loops", t.boundary_loops.len() as f64),
        (
            "boundary_vertices",
            t.boundary_loops.iter().map(Vec::len).sum::<usize>() as f64,
        ),
        (
            "longest_boundary",
            loop_len.iter().cloned().fold(0.0, f64::max),
        ),
        ("components", t.num_face_components() as f64),
        ("isolated_vertices", t.isolated_vertices as f64),
        ("euler_characteristic", t.euler_characteristic() as f64),
        ("genus", t.genus().map_or(-1.0, |g| g as f64)),
        ("manifold", bool_f(t.is_manifold())),
        ("nonmanifold_edges", t.nonmanifold_edges.len() as f64),
        ("nonmanifold_vertices", t.nonmanifold_vertices.len() as f64),
        ("misoriented_edges", t.misoriented_edges.len() as f64),
        ("degenerate_faces", degenerate as f64),
        ("has_uvs", bool_f(mesh.uvs.is_some())),
        ("has_normals", bool_f(mesh.normals.is_some())),
        ("volume", signed_volume(mesh)),
    ]);
    let join = |v: Vec<String>| v.join(" ");
    table.meta.insert(
        "boundary_loop_sizes".into(),
        join(
            t.boundary_loops
                .iter()
                .map(|l| l.len().to_string())
                .collect(),
        ),
    );
    table.meta.insert(
        "boundary_loop_lengths".into(),
        join(loop_len.iter().map(|l| format!("{l}")).collect()),
    );
    if !t.is_manifold() {
        table.meta.insert(
            "manifold_problems".into(),
            format!(
                "{} edges with more than two faces, {} vertices whose faces are not one fan, {} edges with inconsistent orientation",
                t.nonmanifold_edges.len(),
                t.nonmanifold_vertices.len(),
                t.misoriented_edges.len()
            ),
        );
    }
    table
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Counts, bounding box, boundary loops, components, genus and manifoldness of a mesh.");
    b.add_input::<Mesh>("mesh");
    b.add_output::<Table>("table");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let t = mesh_info(&mesh);
    if let Some(p) = t.meta.get("manifold_problems") {
        ctx.log(format!("mesh is not manifold: {p}"));
    }
    let deg = t.column("degenerate_faces").map_or(0.0, |c| c[0]);
    if deg > 0.0 {
        ctx.log(format!("{deg} faces have zero area"));
    }
    ctx.set_output("table", t);
    Ok(())
}

/// Registers `mesh_info`.
pub fn register(r: &mut Registry) {
    r.add("mesh_info", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn get(t: &Table, c: &str) -> f64 {
        t.column(c).unwrap()[0]
    }

    #[test]
    fn unit_square_of_two_triangles() {
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let m = Mesh::from_triangles(p, &[[0, 1, 2], [0, 2, 3]]).unwrap();
        let t = mesh_info(&m);
        assert_eq!(get(&t, "edges"), 5.0);
        assert_eq!(get(&t, "boundary_loops"), 1.0);
        assert_eq!(get(&t, "longest_boundary"), 4.0);
        assert_eq!(get(&t, "area"), 1.0);
        assert_eq!(get(&t, "euler_characteristic"), 1.0);
        assert_eq!(get(&t, "genus"), 0.0);
        assert_eq!(get(&t, "manifold"), 1.0);
        assert_eq!(t.meta["boundary_loop_sizes"], "4");
    }

    #[test]
    fn flags_zero_area_and_non_manifold() {
        // three triangles on edge 0-1, one of them flat (vertex 4 on the edge's line)
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [2.0, 0.0, 0.0],
        ];
        let m = Mesh::from_triangles(p, &[[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
        let t = mesh_info(&m);
        assert_eq!(get(&t, "manifold"), 0.0);
        assert_eq!(get(&t, "nonmanifold_edges"), 1.0);
        assert_eq!(get(&t, "degenerate_faces"), 1.0);
        assert!(t.meta.contains_key("manifold_problems"));
    }
}
