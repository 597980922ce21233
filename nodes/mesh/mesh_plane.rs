//! `mesh_plane`: a flat, subdivided ground plane with planar UVs and normals, for scenes.

use crate::prelude::*;

/// A square plane of side `size` centred at `center`, in the XZ plane facing +Y, split into
/// `n` x `n` quads (two triangles each, counter-clockwise seen from +Y). UVs run over
/// 0..`uv_scale` along +X and -Z (so a texture reads upright from above), normals are +Y.
pub fn plane_mesh(size: f64, center: [f64; 3], n: usize, uv_scale: f64) -> Mesh {
    let n = n.max(1);
    let mut pos = Vec::with_capacity((n + 1) * (n + 1));
    let mut uvs = Vec::with_capacity((n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            let s = i as f64 / n as f64;
            let t = j as f64 / n as f64;
            pos.push([
                center[0] + (s - 0.5) * size,
                center[1],
                center[2] + (0.5 - t) * size,
            ]);
            uvs.push([s * uv_scale, t * uv_scale]);
        }
    }
    // Rows go towards -Z as j grows, so the grid's (i,j),(i+1,j),(i+1,j+1) is CCW from +Y.
    let tris = grid_triangles(n, n);
    let nv = pos.len();
    let mut m = Mesh::from_triangles(pos, &tris).expect("valid indices by construction");
    m.normals = Some(Attribute {
        domain: Domain::Vertex,
        values: vec![[0.0, 1.0, 0.0]; nv],
    });
    m.uvs = Some(Attribute {
        domain: Domain::Vertex,
        values: uvs,
    });
    m
}

/// Turns a Y-up mesh made by `plane_mesh` Z-up: rotates it by +90 degrees about the X
/// axis through `center`, so the normal +Y becomes +Z (for Z-up scenes such as USD's).
pub fn y_up_to_z_up(m: &mut Mesh, center: [f64; 3]) {
    let rot = |p: [f64; 3]| [p[0], -p[2], p[1]];
    for p in &mut m.positions {
        let d = [p[0] - center[0], p[1] - center[1], p[2] - center[2]];
        let r = rot(d);
        *p = [center[0] + r[0], center[1] + r[1], center[2] + r[2]];
    }
    if let Some(n) = &mut m.normals {
        for v in &mut n.values {
            *v = rot(*v);
        }
    }
}

/// The axis a plane faces (the `up` socket).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Up {
    /// Y up: the plane is the XZ plane.
    Y,
    /// Z up: the plane is the XY plane.
    Z,
}

impl Choice for Up {
    const CHOICES: &'static [(&'static str, Self)] = &[("y", Up::Y), ("z", Up::Z)];
}

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
    if !(1..=1024).contains(&n) {
        return Err(NodeError::invalid("subdivisions", "must lie in 1..=1024"));
    }
    if !uv_scale.is_finite() || center.iter().any(|c| !c.is_finite()) {
        return Err(NodeError::invalid("center", "values must be finite"));
    }
    let up = ctx.choice::<Up>("up")?;
    // The grid plus 40 bytes of UV and normal per vertex.
    let nv = (n as u64 + 1) * (n as u64 + 1);
    let bytes = crate::nodes::mesh::mesh_grid::grid_mesh_bytes(n as u64, n as u64, true)
        .saturating_add(crate::node::bytes_of(&[nv, 40]));
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
            let e1 = crate::types::vec3::sub(p(1), p(0));
            let e2 = crate::types::vec3::sub(p(2), p(0));
            let n = crate::types::vec3::cross(e1, e2);
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
