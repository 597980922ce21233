//! Vertex selection by name: the fixed (pinned) vertices of a cloth given as indices, as a
//! named region of the mesh (`top_corners`, `top_edge`, `corners`) or as a per-vertex
//! attribute (`attr:NAME`). A plain function over a mesh, so any node can name vertices the
//! same way.

use cgnodes_api::types::{AttributeData, Domain, Mesh};

/// Vertices named by a selection: `""`/`none`, a list of indices (`"0,39"` or `"0 39"`),
/// `top_corners`, `top_edge`, `corners`, `first_row_ends` (vertices 0 and floor(sqrt(n)) - 1:
/// the two ends of the first row of a square grid, what Framework3D 2024's `MassSpring`
/// fixes), or `attr:NAME` (a vertex attribute, nonzero = selected).
/// `gravity` is the direction gravity pulls (its largest component names the axis; a zero
/// vector means -z). "Top" is against gravity when the mesh extends along it (the lowest
/// coordinate when gravity points along +axis), else along the in-plane axis with the largest
/// extent (y first), so the course's xy grids hang from their y = 1 side.
pub fn select_vertices(
    mesh: &Mesh,
    sel: &str,
    gravity: [f64; 3],
) -> Result<Vec<usize>, SelectionError> {
    let sel = sel.trim();
    let n = mesh.num_vertices();
    if sel.is_empty() || sel == "none" {
        return Ok(Vec::new());
    }
    let tokens: Vec<&str> = sel
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .collect();
    if tokens.iter().all(|t| t.parse::<i64>().is_ok()) {
        let mut out = Vec::new();
        for t in tokens {
            let i: i64 = t.parse().unwrap_or(-1);
            if i < 0 || i as usize >= n {
                return Err(SelectionError::IndexOutOfRange {
                    index: i,
                    vertices: n,
                });
            }
            out.push(i as usize);
        }
        return Ok(out);
    }
    if let Some(name) = sel.strip_prefix("attr:") {
        return attribute_selection(mesh, name);
    }
    if n == 0 {
        return Ok(Vec::new());
    }
    if sel == "first_row_ends" {
        let last = ((n as f64).sqrt().floor() as usize).saturating_sub(1);
        return Ok(if last == 0 { vec![0] } else { vec![0, last] });
    }
    let (lo, hi) = mesh.bounds();
    let ext = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
    let diag = (ext[0] * ext[0] + ext[1] * ext[1] + ext[2] * ext[2]).sqrt();
    let tol = 1e-6 * diag.max(1e-300);
    let g = (0..3)
        .max_by(|&a, &b| gravity[a].abs().total_cmp(&gravity[b].abs()))
        .filter(|&a| gravity[a] != 0.0)
        .unwrap_or(2);
    // Up is against gravity: with gravity along +g the top is the lowest coordinate.
    let (top, top_sign) = if ext[g] > 1e-3 * diag {
        (g, if gravity[g] > 0.0 { -1.0 } else { 1.0 })
    } else {
        let mut best = None;
        for a in [1usize, 2, 0] {
            if a != g && best.is_none_or(|b: usize| ext[a] > ext[b] + tol) {
                best = Some(a);
            }
        }
        (best.unwrap_or(1), 1.0)
    };
    // The side axis: the largest remaining extent, never the gravity axis.
    let side = (0..3)
        .filter(|&a| a != top && a != g)
        .max_by(|&a, &b| ext[a].total_cmp(&ext[b]))
        .unwrap_or((top + 1) % 3);
    let t = |i: usize| top_sign * mesh.positions[i][top];
    let u = |i: usize| mesh.positions[i][side];
    let (et, eu) = (ext[top].max(1e-300), ext[side].max(1e-300));
    let argmax =
        |f: &dyn Fn(usize) -> f64| (0..n).max_by(|&a, &b| f(a).total_cmp(&f(b))).unwrap_or(0);
    match sel {
        "top_edge" => {
            let tmax = (0..n).map(t).fold(f64::NEG_INFINITY, f64::max);
            Ok((0..n).filter(|&i| t(i) >= tmax - tol).collect())
        }
        "top_corners" => {
            let a = argmax(&|i| t(i) / et + u(i) / eu);
            let b = argmax(&|i| t(i) / et - u(i) / eu);
            Ok(if a == b { vec![a] } else { vec![a, b] })
        }
        "corners" => {
            let mut out = Vec::new();
            for (st, su) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                let c = argmax(&|i| st * t(i) / et + su * u(i) / eu);
                if !out.contains(&c) {
                    out.push(c);
                }
            }
            Ok(out)
        }
        other => Err(SelectionError::Unknown(other.to_string())),
    }
}

/// `attr:NAME`: the vertices where the per-vertex float or integer attribute `name` is non-zero.
fn attribute_selection(mesh: &Mesh, name: &str) -> Result<Vec<usize>, SelectionError> {
    let n = mesh.num_vertices();
    let a = mesh
        .attributes
        .get(name)
        .ok_or_else(|| SelectionError::NoAttribute(name.to_string()))?;
    let vals: Vec<f64> = match a {
        AttributeData::Float(a) if a.domain == Domain::Vertex => a.values.clone(),
        AttributeData::Int(a) if a.domain == Domain::Vertex => {
            a.values.iter().map(|&v| v as f64).collect()
        }
        _ => return Err(SelectionError::NotPerVertex(name.to_string())),
    };
    Ok((0..n)
        .filter(|&i| vals.get(i).is_some_and(|v| *v != 0.0))
        .collect())
}

/// Why a vertex selection cannot be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SelectionError {
    /// An index past the mesh's vertices (or negative).
    #[error("vertex index {index} is outside 0..{vertices}")]
    IndexOutOfRange {
        /// The index given.
        index: i64,
        /// The mesh's vertex count.
        vertices: usize,
    },
    /// `attr:NAME` naming no attribute of the mesh.
    #[error("the mesh has no attribute '{0}'")]
    NoAttribute(String),
    /// `attr:NAME` naming an attribute that is not a per-vertex float or integer.
    #[error("attribute '{0}' is not a per-vertex number")]
    NotPerVertex(String),
    /// A selection that is none of the known forms.
    #[error("'{0}' is not a selection: use indices like \"0,39\", top_corners, top_edge, corners, first_row_ends, attr:NAME or none")]
    Unknown(String),
}

/// The nodes report errors as text: the message unchanged.
impl From<SelectionError> for String {
    fn from(e: SelectionError) -> String {
        e.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cgnodes_api::types::Attribute;

    /// Gravity along -z, as in the course.
    const DOWN_Z: [f64; 3] = [0.0, 0.0, -9.8];

    /// The vertices of a `cells x cells` grid of `size` centred at the origin in the plane of
    /// axes `(au, av)`, vertex `(i, j)` at index `j * (cells + 1) + i` (as `mesh_grid` orders them).
    fn grid(cells: usize, size: f64, au: usize, av: usize) -> Mesh {
        let mut m = Mesh::default();
        for j in 0..=cells {
            for i in 0..=cells {
                let mut p = [0.0; 3];
                p[au] += size * (i as f64 / cells as f64 - 0.5);
                p[av] += size * (j as f64 / cells as f64 - 0.5);
                m.positions.push(p);
            }
        }
        m
    }

    #[test]
    fn first_row_ends_are_framework3ds_fixed_pair() {
        // 5 x 5 vertices: 0 and sqrt(25) - 1 = 4, whatever the grid's orientation
        let g = grid(4, 1.0, 0, 1);
        assert_eq!(
            select_vertices(&g, "first_row_ends", DOWN_Z).unwrap(),
            vec![0, 4]
        );
        // not a square count: floor(sqrt(30)) - 1 = 4
        let mut m = g.clone();
        m.positions.extend(vec![[0.0; 3]; 5]);
        assert_eq!(
            select_vertices(&m, "first_row_ends", DOWN_Z).unwrap(),
            vec![0, 4]
        );
    }

    #[test]
    fn selections() {
        let m = grid(10, 2.0, 0, 1);
        assert_eq!(
            select_vertices(&m, "top_corners", DOWN_Z).unwrap(),
            vec![120, 110]
        );
        assert_eq!(select_vertices(&m, "0, 39", DOWN_Z).unwrap(), vec![0, 39]);
        assert_eq!(
            select_vertices(&m, "top_edge", DOWN_Z).unwrap(),
            (110..121).collect::<Vec<_>>()
        );
        let mut c = select_vertices(&m, "corners", DOWN_Z).unwrap();
        c.sort();
        assert_eq!(c, vec![0, 10, 110, 120]);
        assert!(select_vertices(&m, "", DOWN_Z).unwrap().is_empty());
        assert!(select_vertices(&m, "121", DOWN_Z).is_err());
        // A vertical cloth (xz plane) hangs from its highest side along gravity (z).
        let v = grid(4, 1.0, 0, 2);
        assert_eq!(
            select_vertices(&v, "top_corners", DOWN_Z).unwrap(),
            vec![24, 20]
        );
        let mut a = m.clone();
        let vals = (0..121).map(|i| if i == 5 { 1.0 } else { 0.0 }).collect();
        a.attributes.insert(
            "pin".into(),
            AttributeData::Float(Attribute {
                domain: Domain::Vertex,
                values: vals,
            }),
        );
        assert_eq!(select_vertices(&a, "attr:pin", DOWN_Z).unwrap(), vec![5]);
    }

    /// Issue 23: "top" is against gravity, whichever sign gravity has.
    #[test]
    fn top_is_against_gravity_of_either_sign() {
        // A vertical cloth (xz plane): gravity along -z hangs it from z = +0.5, along +z
        // from z = -0.5.
        let v = grid(4, 1.0, 0, 2);
        assert_eq!(
            select_vertices(&v, "top_corners", DOWN_Z).unwrap(),
            vec![24, 20]
        );
        let up_z = [0.0, 0.0, 9.8];
        assert_eq!(
            select_vertices(&v, "top_corners", up_z).unwrap(),
            vec![4, 0]
        );
        assert_eq!(
            select_vertices(&v, "top_edge", up_z).unwrap(),
            (0..5).collect::<Vec<_>>()
        );
        // An xy cloth with gravity along y: -y pins the y = +1 corners, +y the y = -1 ones.
        let m = grid(10, 2.0, 0, 1);
        assert_eq!(
            select_vertices(&m, "top_corners", [0.0, -1.0, 0.0]).unwrap(),
            vec![120, 110]
        );
        assert_eq!(
            select_vertices(&m, "top_corners", [0.0, 1.0, 0.0]).unwrap(),
            vec![10, 0]
        );
        // A zero vector means the default, -z.
        assert_eq!(
            select_vertices(&v, "top_corners", [0.0; 3]).unwrap(),
            vec![24, 20]
        );
    }
}
