//! `mesh_uv_project`: planar UVs by projecting positions along an axis, so meshes without
//! a parameterization can carry a texture in a scene.

use cgnodes_api::prelude::*;

/// Per-vertex UVs from the orthographic projection along `axis` (0 = x, 1 = y, 2 = z):
/// the two other coordinates are mapped so that the
/// longer side of the bounding box spans `0..scale`. For `axis` x the UV axes are (z, y),
/// for y they are (x, -z), for z they are (x, y): each reads upright seen from the + side.
pub fn planar_uvs(mesh: &Mesh, axis: usize, scale: f64) -> Vec<[f64; 2]> {
    let (lo, hi) = mesh.bounds();
    let (a, b, sa, sb) = match axis {
        0 => (2, 1, -1.0, 1.0),
        1 => (0, 2, 1.0, -1.0),
        _ => (0, 1, 1.0, 1.0),
    };
    let ext = (hi[a] - lo[a]).max(hi[b] - lo[b]).max(1e-300);
    mesh.positions
        .iter()
        .map(|p| {
            let u = if sa > 0.0 { p[a] - lo[a] } else { hi[a] - p[a] };
            let v = if sb > 0.0 { p[b] - lo[b] } else { hi[b] - p[b] };
            [u / ext * scale, v / ext * scale]
        })
        .collect()
}

/// The projection axis of the `axis` socket, as a coordinate index for `planar_uvs`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct ProjectionAxis(usize);

impl Choice for ProjectionAxis {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("z", ProjectionAxis(2)),
        ("x", ProjectionAxis(0)),
        ("y", ProjectionAxis(1)),
    ];
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Planar UVs: projects the mesh along an axis onto its bounding box.");
    b.add_input::<Mesh>("mesh");
    b.add_choice::<ProjectionAxis>("axis")
        .doc("Projection direction.");
    b.add_input::<f64>("scale")
        .default(1.0)
        .doc("UVs span 0..scale over the longer side.");
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let ProjectionAxis(ax) = ctx.choice::<ProjectionAxis>("axis")?;
    let scale: f64 = ctx.input("scale")?;
    if !scale.is_finite() {
        return Err(NodeError::invalid("scale", "must be finite"));
    }
    let mut m = (*mesh).clone();
    m.uvs = Some(Attribute {
        domain: Domain::Vertex,
        values: planar_uvs(&mesh, ax, scale),
    });
    ctx.set_output("mesh", m);
    Ok(())
}

/// Registers `mesh_uv_project`.
pub fn register(r: &mut Registry) {
    r.add("mesh_uv_project", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_along_z_maps_the_box_to_the_unit_square() {
        let m = Mesh::from_triangles(
            vec![[1.0, 2.0, 5.0], [3.0, 2.0, 0.0], [1.0, 3.0, 1.0]],
            &[[0, 1, 2]],
        )
        .unwrap();
        let uv = planar_uvs(&m, 2, 1.0);
        assert_eq!(uv, vec![[0.0, 0.0], [1.0, 0.0], [0.0, 0.5]]);
        let uv = planar_uvs(&m, 1, 2.0);
        // Along y: u = x, v = -z over the longer side (z: 5).
        assert_eq!(uv[0], [0.0, 0.0]);
        assert_eq!(uv[1], [0.8, 2.0]);
    }
}
