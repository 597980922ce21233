//! `mesh_plane`: a flat, subdivided ground plane with planar UVs and normals, for scenes.

use cgnodes_api::prelude::*;
pub use cgnodes_geometry::plane::*;

fn declare(b: &mut NodeBuilder) {
    b.doc("A flat square plane facing +Y with planar UVs (a ground plane).");
    b.add_input::<f64>("size")
        .default(4.0)
        .min(1e-9)
        .doc("Side length.");
    b.add_input::<[f64; 3]>("center")
        .default([0.0, 0.0, 0.0])
        .doc("Centre of the plane.");
    b.add_input::<i64>("subdivisions")
        .default(1i64)
        .range(1.0, 1024.0)
        .doc("Quads per side.");
    b.add_input::<f64>("uv_scale")
        .default(1.0)
        .doc("UVs run from 0 to uv_scale (texture repeats).");
    b.add_choice::<Up>("up")
        .doc("Axis the plane faces (y: XZ plane; z: XY plane, for Z-up scenes).");
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let size: f64 = ctx.input("size")?;
    let center: [f64; 3] = ctx.input("center")?;
    let n: i64 = ctx.input("subdivisions")?;
    let uv_scale: f64 = ctx.input("uv_scale")?;
    if !(size > 0.0 && size.is_finite()) {
        return Err(NodeError::invalid("size", "must be positive"));
    }
    if !uv_scale.is_finite() || center.iter().any(|c| !c.is_finite()) {
        return Err(NodeError::invalid("center", "values must be finite"));
    }
    let up = ctx.choice::<Up>("up")?;
    // The grid plus 40 bytes of UV and normal per vertex.
    let nv = (n as u64 + 1) * (n as u64 + 1);
    let bytes = cgnodes_geometry::grid::grid_mesh_bytes(n as u64, n as u64, true)
        .saturating_add(cgnodes_api::node::bytes_of(&[nv, 40]));
    ctx.reserve_bytes("subdivisions", &format!("a {n}x{n} plane"), bytes)?;
    let mut m = plane_mesh(size, center, n as usize, uv_scale);
    if up == Up::Z {
        y_up_to_z_up(&mut m, center);
    }
    ctx.set_output("mesh", m);
    Ok(())
}

/// Registers `mesh_plane`.
pub fn register(r: &mut Registry) {
    r.add("mesh_plane", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_faces_up_with_planar_uvs() {
        let m = plane_mesh(2.0, [0.0, 1.0, 0.0], 3, 1.0);
        assert_eq!(m.num_faces(), 18);
        assert_eq!(m.bounds(), ([-1.0, 1.0, -1.0], [1.0, 1.0, 1.0]));
        for t in m.triangles().unwrap() {
            let p = |k: usize| m.positions[t[k] as usize];
            let e1 = cgnodes_api::types::vec3::sub(p(1), p(0));
            let e2 = cgnodes_api::types::vec3::sub(p(2), p(0));
            let n = cgnodes_api::types::vec3::cross(e1, e2);
            assert!(n[1] > 0.0 && n[0].abs() < 1e-12 && n[2].abs() < 1e-12);
        }
        let mut z = m.clone();
        y_up_to_z_up(&mut z, [0.0, 1.0, 0.0]);
        // Rotated about the X axis through the centre: the XY plane at z = center.z.
        assert_eq!(z.bounds(), ([-1.0, 0.0, 0.0], [1.0, 2.0, 0.0]));
        assert_eq!(z.normals.as_ref().unwrap().values[0], [0.0, 0.0, 1.0]);
        let uv = &m.uvs.as_ref().unwrap().values;
        // UV u follows x, v follows -z.
        for (p, t) in m.positions.iter().zip(uv) {
            assert!((t[0] - (p[0] + 1.0) / 2.0).abs() < 1e-12);
            assert!((t[1] - (1.0 - p[2]) / 2.0).abs() < 1e-12);
        }
    }
}
