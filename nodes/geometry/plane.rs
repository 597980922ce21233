//! A square plane mesh with UVs, Y-up or turned Z-up (`mesh_plane`, ground planes).

use cgnodes_api::prelude::*;

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
pub enum Up {
    /// Y up: the plane is the XZ plane.
    Y,
    /// Z up: the plane is the XY plane.
    Z,
}

impl Choice for Up {
    const CHOICES: &'static [(&'static str, Self)] = &[("y", Up::Y), ("z", Up::Z)];
}
