//! `gaussian_curvature`: the discrete Gaussian curvature of each vertex by the angle defect
//! (Descartes; Meyer et al. 2003, "Discrete Differential-Geometry Operators for Triangulated
//! 2-Manifolds", eq. 9 with the barycentric area), as Framework3D's `geom_curvature` computes
//! it: `K_v = (2 pi - sum of the corner angles at v) / (A_v / 3)`, `A_v` the area of the
//! triangles around v.

use cgnodes_api::prelude::*;

/// Per-vertex angle defect `2 pi - sum theta` (interior) or `pi - sum theta` (boundary, the
/// turning of the boundary curve) and barycentric area `A_v / 3` of a triangle mesh.
/// Isolated vertices have defect 0 and area 0.
pub fn angle_defects(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    boundary: &[bool],
) -> (Vec<f64>, Vec<f64>) {
    let n = positions.len();
    let mut theta = vec![0.0; n];
    let mut area = vec![0.0; n];
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    for t in triangles {
        let p = t.map(|i| positions[i as usize]);
        let (e1, e2) = (sub(p[1], p[0]), sub(p[2], p[0]));
        let c = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let a = dot(c, c).sqrt() / 2.0;
        for k in 0..3 {
            let (u, v) = (sub(p[(k + 1) % 3], p[k]), sub(p[(k + 2) % 3], p[k]));
            let cos = dot(u, v) / (dot(u, u) * dot(v, v)).sqrt();
            let i = t[k] as usize;
            if cos.is_finite() {
                theta[i] += cos.clamp(-1.0, 1.0).acos();
            }
            area[i] += a / 3.0;
        }
    }
    let defect = (0..n)
        .map(|i| {
            if area[i] == 0.0 {
                0.0
            } else if boundary[i] {
                std::f64::consts::PI - theta[i]
            } else {
                2.0 * std::f64::consts::PI - theta[i]
            }
        })
        .collect();
    (defect, area)
}

/// A mesh with faces that triangulation could not split.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("the mesh has faces that could not be triangulated")]
pub struct NotTriangulated;

/// Gaussian curvature per vertex: angle defect over barycentric area (0 where the area is 0).
pub fn gaussian_curvature(mesh: &Arc<Mesh>) -> Result<Vec<f64>, NotTriangulated> {
    let tris = mesh.triangulated();
    let tris = tris.triangles().ok_or(NotTriangulated)?;
    let topo = mesh.topology();
    let boundary: Vec<bool> = (0..mesh.num_vertices())
        .map(|v| topo.is_boundary_vertex(v))
        .collect();
    let (defect, area) = angle_defects(&mesh.positions, &tris, &boundary);
    Ok(defect
        .iter()
        .zip(&area)
        .map(|(d, a)| if *a > 0.0 { d / a } else { 0.0 })
        .collect())
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Discrete Gaussian curvature per vertex: angle defect over a third of the surrounding triangles' area (Framework3D's Curvature node).");
    b.add_input::<Mesh>("mesh");
    b.add_output::<Vec<f64>>("curvature")
        .doc("One value per vertex (1/r^2 on a sphere of radius r).");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let k = gaussian_curvature(&mesh).map_err(|e| NodeError::invalid("mesh", e.to_string()))?;
    ctx.set_output("curvature", k);
    Ok(())
}

/// Registers `gaussian_curvature`.
pub fn register(r: &mut Registry) {
    r.add("gaussian_curvature", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn octahedron(r: f64) -> Mesh {
        use cgnodes_geometry::octahedron;
        Mesh::from_triangles(
            octahedron::positions([0.0; 3], r).to_vec(),
            &octahedron::FACES,
        )
        .unwrap()
    }

    #[test]
    fn octahedron_matches_hand_values_and_gauss_bonnet() {
        let r = 2.0;
        let m = octahedron(r);
        let k = gaussian_curvature(&Arc::new(m)).unwrap();
        // Each vertex: four 60-degree corners (defect 2pi/3) and four faces of area
        // sqrt(3)/4 * (r sqrt 2)^2, a third of each.
        let face = 3f64.sqrt() / 4.0 * 2.0 * r * r;
        let want = (2.0 * PI / 3.0) / (4.0 * face / 3.0);
        for x in &k {
            assert!((x - want).abs() < 1e-12, "{x} against {want}");
        }
        // Gauss-Bonnet: sum of K_v A_v = 2 pi chi = 4 pi.
        let total: f64 = k.iter().map(|x| x * 4.0 * face / 3.0).sum();
        assert!((total - 4.0 * PI).abs() < 1e-12);
    }

    #[test]
    fn flat_grid_interior_is_zero() {
        let g = cgnodes_geometry::grid::grid_mesh(4, 4, [1.0, 1.0], "xy", [0.0; 3], true).unwrap();
        let k = gaussian_curvature(&Arc::new(g)).unwrap();
        // Interior vertex (2, 2): index 2 * 5 + 2; corner angles sum to 2 pi.
        assert!(k[12].abs() < 1e-9);
        // A boundary edge vertex (not a corner) turns by 0 too.
        assert!(k[2].abs() < 1e-9);
        // A corner of the square turns by pi/2.
        assert!(k[0] > 0.0);
    }
}
