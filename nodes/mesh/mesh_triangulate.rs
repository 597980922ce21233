//! `mesh_triangulate`: splits polygons into triangles by ear clipping (Meisters 1975,
//! "Polygons have ears"; Eberly, "Triangulation by Ear Clipping"), on the plane of each
//! polygon's Newell normal, so non-convex polygons stay inside their outline. Convex quads
//! are split along their shorter diagonal. Per-corner and per-face data follow.

use crate::prelude::*;
use crate::types::vec3;

fn newell(p: &[[f64; 3]]) -> [f64; 3] {
    let mut n = [0.0; 3];
    for k in 0..p.len() {
        let a = p[k];
        let b = p[(k + 1) % p.len()];
        n[0] += (a[1] - b[1]) * (a[2] + b[2]);
        n[1] += (a[2] - b[2]) * (a[0] + b[0]);
        n[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    n
}

/// Twice the signed area of the triangle `o, a, b` (positive when counter-clockwise).
fn cross2(o: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    vec3::cross2(vec3::sub2(a, o), vec3::sub2(b, o))
}

/// Triangles (as local corner indices) covering a simple polygon given by its 3-D corners,
/// in the polygon's winding. Degenerate or self-intersecting input still yields
/// `n - 2` triangles (the remaining corners are fanned once no ear is found).
pub fn triangulate_polygon(p: &[[f64; 3]]) -> Vec<[usize; 3]> {
    let n = p.len();
    if n < 3 {
        return Vec::new();
    }
    if n == 3 {
        return vec![[0, 1, 2]];
    }
    // Project onto the coordinate plane most aligned with the normal, keeping the winding
    // counter-clockwise in 2-D.
    let nn = newell(p);
    let ax = (0..3)
        .max_by(|&a, &b| nn[a].abs().total_cmp(&nn[b].abs()))
        .unwrap_or(2);
    let (mut u, mut v) = ((ax + 1) % 3, (ax + 2) % 3);
    if nn[ax] < 0.0 {
        std::mem::swap(&mut u, &mut v);
    }
    let q: Vec<[f64; 2]> = p.iter().map(|x| [x[u], x[v]]).collect();
    let d2 = |a: usize, b: usize| (0..3).map(|k| (p[a][k] - p[b][k]).powi(2)).sum::<f64>();
    if n == 4 {
        let convex = (0..4).all(|k| cross2(q[(k + 3) % 4], q[k], q[(k + 1) % 4]) > 0.0);
        if convex {
            return if d2(0, 2) <= d2(1, 3) {
                vec![[0, 1, 2], [0, 2, 3]]
            } else {
                vec![[0, 1, 3], [1, 2, 3]]
            };
        }
    }
    let mut rem: Vec<usize> = (0..n).collect();
    let mut out = Vec::with_capacity(n - 2);
    while rem.len() > 3 {
        let m = rem.len();
        let mut found = None;
        for i in 0..m {
            let (a, b, c) = (rem[(i + m - 1) % m], rem[i], rem[(i + 1) % m]);
            if cross2(q[a], q[b], q[c]) <= 0.0 {
                continue; // reflex or flat corner
            }
            let inside = rem.iter().any(|&o| {
                o != a
                    && o != b
                    && o != c
                    && cross2(q[a], q[b], q[o]) >= 0.0
                    && cross2(q[b], q[c], q[o]) >= 0.0
                    && cross2(q[c], q[a], q[o]) >= 0.0
            });
            if !inside {
                found = Some(i);
                break;
            }
        }
        let i = found.unwrap_or(1);
        let m = rem.len();
        out.push([rem[(i + m - 1) % m], rem[i], rem[(i + 1) % m]]);
        rem.remove(i);
    }
    out.push([rem[0], rem[1], rem[2]]);
    out
}

/// A copy of `mesh` with every face split into triangles; returns the mesh and how many
/// polygons (faces with more than 3 corners) were split.
pub fn triangulate(mesh: &Mesh) -> (Mesh, usize) {
    let starts = mesh.face_starts();
    let mut idx = Vec::new();
    let mut corner_src = Vec::new();
    let mut face_src = Vec::new();
    let mut split = 0;
    for (f, face) in mesh.faces().enumerate() {
        let s = starts[f] as usize;
        if face.len() > 3 {
            split += 1;
        }
        let pts: Vec<[f64; 3]> = face.iter().map(|&v| mesh.positions[v as usize]).collect();
        for t in triangulate_polygon(&pts) {
            for k in t {
                idx.push(face[k]);
                corner_src.push(s + k);
            }
            face_src.push(f);
        }
    }
    fn re<T: Clone>(a: &Attribute<T>, c: &[usize], f: &[usize]) -> Attribute<T> {
        let map = match a.domain {
            Domain::Vertex => return a.clone(),
            Domain::Corner => c,
            Domain::Face => f,
        };
        Attribute {
            domain: a.domain,
            values: map.iter().map(|&i| a.values[i].clone()).collect(),
        }
    }
    let mut out = mesh.clone();
    let nt = face_src.len();
    out.set_faces(vec![3; nt], idx);
    let (c, f) = (&corner_src[..], &face_src[..]);
    out.uvs = mesh.uvs.as_ref().map(|a| re(a, c, f));
    out.normals = mesh.normals.as_ref().map(|a| re(a, c, f));
    out.colors = mesh.colors.as_ref().map(|a| re(a, c, f));
    out.attributes = mesh
        .attributes
        .iter()
        .map(|(k, a)| {
            let na = match a {
                AttributeData::Float(a) => AttributeData::Float(re(a, c, f)),
                AttributeData::Vec2(a) => AttributeData::Vec2(re(a, c, f)),
                AttributeData::Vec3(a) => AttributeData::Vec3(re(a, c, f)),
                AttributeData::Int(a) => AttributeData::Int(re(a, c, f)),
            };
            (k.clone(), na)
        })
        .collect();
    (out, split)
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Splits polygon faces into triangles (ear clipping; per-corner data follow).");
    b.add_input::<Mesh>("mesh");
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    if mesh.is_triangle_mesh() {
        ctx.log("already all triangles");
        ctx.set_output("mesh", mesh);
        return Ok(());
    }
    let (out, split) = triangulate(&mesh);
    ctx.log(format!(
        "split {split} polygons: {} faces -> {} triangles",
        mesh.num_faces(),
        out.num_faces()
    ));
    ctx.set_output("mesh", out);
    Ok(())
}

/// Registers `mesh_triangulate`.
pub fn register(r: &mut Registry) {
    r.add("mesh_triangulate", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area2(q: &[[f64; 3]], t: [usize; 3]) -> f64 {
        let (a, b, c) = (q[t[0]], q[t[1]], q[t[2]]);
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    }

    #[test]
    fn concave_polygon_stays_inside_and_keeps_area() {
        // An L shape (area 3) whose fan from corner 0 would leave the outline.
        let p = vec![
            [1.0, 1.0, 0.0],
            [1.0, 2.0, 0.0],
            [0.0, 2.0, 0.0],
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 1.0, 0.0],
        ];
        let t = triangulate_polygon(&p);
        assert_eq!(t.len(), 4);
        let total: f64 = t.iter().map(|&t| area2(&p, t) / 2.0).sum();
        assert!((total - 3.0).abs() < 1e-12);
        // every triangle is counter-clockwise like the polygon: none folds over
        assert!(t.iter().all(|&t| area2(&p, t) > 0.0));
    }

    #[test]
    fn quads_split_on_the_shorter_diagonal_and_uvs_follow() {
        let p = vec![
            [0.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [4.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
        ];
        let mut m = Mesh::new(p, vec![4], vec![0, 1, 2, 3]).unwrap();
        m.uvs = Some(Attribute {
            domain: Domain::Corner,
            values: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        });
        let (t, split) = triangulate(&m);
        assert_eq!(split, 1);
        // diagonal 1-3 (length sqrt 5) is shorter than 0-2 (sqrt 17)
        assert_eq!(t.face_indices(), &[0, 1, 3, 1, 2, 3]);
        assert_eq!(t.uvs.as_ref().unwrap().values[2], [0.0, 1.0]);
        t.check().unwrap();
    }
}
