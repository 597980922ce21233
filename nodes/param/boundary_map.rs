//! `boundary_map`: places a disk mesh's boundary loop on a circle or a square in [0,1]^2,
//! the first step of Tutte's embedding (Tutte 1963; Floater 1997).
//!
//! Arc-length spacing as in the USTC course: each boundary vertex goes to its fraction of the
//! loop's length. The circle (centre (1/2, 1/2), radius 1/2) starts at (1, 1/2); the square
//! starts at (0, 0); both run counter-clockwise, so triangles whose boundary loop runs
//! counter-clockwise around them (outward-facing) stay counter-clockwise in UV. On the square the
//! four vertices nearest to the quarter fractions are snapped to the corners and the others are
//! spaced along the sides between them; without the snapping a corner would be cut off and
//! boundary triangles with three vertices on one side would collapse.

use cgnodes_api::prelude::*;

/// The convex shape the boundary is mapped to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundaryShape {
    /// Circle of radius 1/2 centred at (1/2, 1/2), starting at (1, 1/2).
    Circle,
    /// The unit square [0,1]^2, starting at (0, 0).
    Square,
}

impl Choice for BoundaryShape {
    const CHOICES: &'static [(&'static str, Self)] =
        &[("circle", Self::Circle), ("square", Self::Square)];
}

/// How boundary vertices are spaced along the shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Spacing {
    /// By fraction of the loop's 3D length.
    ArcLength,
    /// Equally, by vertex count.
    Uniform,
}

impl Choice for Spacing {
    const CHOICES: &'static [(&'static str, Self)] =
        &[("arc_length", Self::ArcLength), ("uniform", Self::Uniform)];
}

/// UVs of the vertices of `boundary` (in loop order, first vertex at the start point), placed on
/// `shape` counter-clockwise.
pub fn map_boundary(
    positions: &[[f64; 3]],
    boundary: &[u32],
    shape: BoundaryShape,
    spacing: Spacing,
) -> Result<Vec<[f64; 2]>, String> {
    let n = boundary.len();
    if n < 3 {
        return Err(format!(
            "boundary loop has {n} vertices; at least 3 are needed"
        ));
    }
    if shape == BoundaryShape::Square && n < 4 {
        return Err("boundary loop has 3 vertices; a square boundary needs at least 4".into());
    }
    // Cumulative fraction t_i in [0, 1) of each vertex along the loop.
    let mut t = Vec::with_capacity(n);
    match spacing {
        Spacing::Uniform => t.extend((0..n).map(|i| i as f64 / n as f64)),
        Spacing::ArcLength => {
            let mut acc = 0.0;
            let len = |i: usize| {
                let a = positions[boundary[i] as usize];
                let b = positions[boundary[(i + 1) % n] as usize];
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
            };
            for i in 0..n {
                t.push(acc);
                acc += len(i);
            }
            if acc <= 0.0 || !acc.is_finite() {
                return Err("boundary loop has zero or non-finite length".into());
            }
            if (0..n).any(|i| len(i) <= 0.0) {
                return Err("boundary loop has a zero-length edge (duplicate vertices)".into());
            }
            for x in &mut t {
                *x /= acc;
            }
        }
    }
    Ok(match shape {
        BoundaryShape::Circle => t
            .iter()
            .map(|&s| {
                let a = std::f64::consts::TAU * s;
                [0.5 + 0.5 * a.cos(), 0.5 + 0.5 * a.sin()]
            })
            .collect(),
        BoundaryShape::Square => {
            // Corner c (at fraction c/4) goes to the vertex nearest that fraction, keeping
            // the four corners distinct and in order.
            let mut corner = [0usize; 5];
            for c in 1..4 {
                let target = c as f64 / 4.0;
                let mut best = (0..n)
                    .min_by(|&a, &b| (t[a] - target).abs().total_cmp(&(t[b] - target).abs()))
                    .unwrap_or(0);
                best = best.max(corner[c - 1] + 1).min(n - (4 - c));
                corner[c] = best;
            }
            corner[4] = n;
            let mut uv = vec![[0.0; 2]; n];
            let frac = |i: usize| if i == n { 1.0 } else { t[i] };
            for side in 0..4 {
                let (a, b) = (corner[side], corner[side + 1]);
                for (i, slot) in uv.iter_mut().enumerate().take(b).skip(a) {
                    let s = (frac(i) - frac(a)) / (frac(b) - frac(a));
                    *slot = match side {
                        0 => [s, 0.0],
                        1 => [1.0, s],
                        2 => [1.0 - s, 1.0],
                        _ => [0.0, 1.0 - s],
                    };
                }
            }
            uv
        }
    })
}

/// The mesh's single boundary loop, rotated to start at `start_vertex` (when given).
pub fn boundary_loop(mesh: &Mesh, start_vertex: Option<u32>) -> Result<Vec<u32>, NodeError> {
    let topo = mesh.topology();
    let loops = &topo.boundary_loops;
    match loops.len() {
        0 => {
            return Err(NodeError::topology(
                "mesh",
                "mesh is closed (no boundary loop); a disk is needed: cut it open first",
            ))
        }
        1 => {}
        n => {
            return Err(NodeError::topology(
                "mesh",
                format!("mesh has {n} boundary loops; a disk is needed; use holes: fill"),
            ))
        }
    }
    rotate_loop(&loops[0], start_vertex)
}

/// `lp` rotated to start at `start` (when given); an error if `start` is not on the loop.
pub fn rotate_loop(lp: &[u32], start: Option<u32>) -> Result<Vec<u32>, NodeError> {
    let mut lp = lp.to_vec();
    if let Some(s) = start {
        let k = lp.iter().position(|&v| v == s).ok_or_else(|| {
            NodeError::invalid(
                "start_vertex",
                format!("vertex {s} is not on the mapped boundary loop"),
            )
        })?;
        lp.rotate_left(k);
    }
    Ok(lp)
}

pub(crate) fn parse_start(v: i64) -> Option<u32> {
    (v >= 0).then_some(v as u32)
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Places a disk mesh's boundary loop on a circle or square in [0,1]^2 (positions of boundary vertices become (u, v, 0); UVs set on them).");
    b.add_input::<Mesh>("mesh");
    b.add_choice::<BoundaryShape>("shape");
    b.add_choice::<Spacing>("spacing")
        .doc("arc_length: by fraction of the loop's length; uniform: by vertex count.");
    b.add_input::<i64>("start_vertex")
        .default(-1i64)
        .doc("Boundary vertex placed at the start point; -1: the loop's first vertex.");
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let shape = ctx.choice::<BoundaryShape>("shape")?;
    let spacing = ctx.choice::<Spacing>("spacing")?;
    let start = parse_start(ctx.input("start_vertex")?);
    let lp = boundary_loop(&mesh, start)?;
    let uv = map_boundary(&mesh.positions, &lp, shape, spacing)
        .map_err(|m| NodeError::topology("mesh", m))?;
    let mut out = (*mesh).clone();
    let mut uvs = vec![[0.0; 2]; out.num_vertices()];
    for (&v, t) in lp.iter().zip(&uv) {
        out.positions[v as usize] = [t[0], t[1], 0.0];
        uvs[v as usize] = *t;
    }
    out.uvs = Some(Attribute {
        domain: Domain::Vertex,
        values: uvs,
    });
    ctx.log(format!("{} boundary vertices mapped", lp.len()));
    ctx.set_output("mesh", out);
    Ok(())
}

/// Registers `boundary_map`.
pub fn register(r: &mut Registry) {
    r.add("boundary_map", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_starts_at_one_half_and_runs_ccw() {
        // a unit square loop of 4 equal edges: quarter turns
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let uv =
            map_boundary(&p, &[0, 1, 2, 3], BoundaryShape::Circle, Spacing::ArcLength).unwrap();
        let want = [[1.0, 0.5], [0.5, 1.0], [0.0, 0.5], [0.5, 0.0]];
        for (a, b) in uv.iter().zip(want) {
            assert!((a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12);
        }
    }

    #[test]
    fn square_arc_length_uses_fractions_and_snaps_corners() {
        // 8 vertices, edge lengths 1,1,1,1,1,1,1,1 -> two per side
        let p: Vec<[f64; 3]> = (0..8)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / 8.0;
                [a.cos(), a.sin(), 0.0]
            })
            .collect();
        let lp: Vec<u32> = (0..8).collect();
        let uv = map_boundary(&p, &lp, BoundaryShape::Square, Spacing::ArcLength).unwrap();
        let want = [
            [0.0, 0.0],
            [0.5, 0.0],
            [1.0, 0.0],
            [1.0, 0.5],
            [1.0, 1.0],
            [0.5, 1.0],
            [0.0, 1.0],
            [0.0, 0.5],
        ];
        for (a, b) in uv.iter().zip(want) {
            assert!(
                (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12,
                "{a:?} {b:?}"
            );
        }
        // uneven lengths: first edge 3x longer than the others (6 vertices)
        let p = vec![
            [0.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [3.0, 1.0, 0.0],
            [2.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let uv = map_boundary(
            &p,
            &[0, 1, 2, 3, 4, 5],
            BoundaryShape::Circle,
            Spacing::ArcLength,
        )
        .unwrap();
        // vertex 1 at fraction 3/8 of the length 8
        let a = std::f64::consts::TAU * 3.0 / 8.0;
        assert!((uv[1][0] - (0.5 + 0.5 * a.cos())).abs() < 1e-12);
    }

    #[test]
    fn too_short_loops_are_refused() {
        let p = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(map_boundary(&p, &[0, 1, 2], BoundaryShape::Square, Spacing::Uniform).is_err());
        assert!(map_boundary(&p, &[0, 1], BoundaryShape::Circle, Spacing::Uniform).is_err());
    }
}
