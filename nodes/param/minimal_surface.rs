//! `minimal_surface`: the discrete minimal surface spanning a mesh's boundary.
//!
//! Solves the Laplace equation `sum_j w_ij (x_i - x_j) = 0` for every interior vertex with the
//! boundary vertices (all loops) fixed at their own positions: one linear step towards the
//! minimal surface (Pinkall and Polthier 1993) with uniform weights (the membrane of the USTC
//! course) or cotangent weights taken from the input geometry. The three coordinates share one
//! sparse Cholesky factorization.

use super::laplacian::mean_value_weights;
use super::laplacian_rows::LaplacianRows;
use super::triangles::fan_triangles;
use super::tutte::TutteWeights;
use cgnodes_api::prelude::*;
use cgnodes_linalg::laplace::solve_dirichlet;
use cgnodes_linalg::laplace_weights::solve_dirichlet_weights;

/// The minimal surface's vertex positions: interior vertices solved, boundary vertices (and
/// vertices used by no face) kept. `weights` is `Uniform` or `Cotangent` (mean-value weights
/// also work and use a sparse LU). Returns the positions and the number of edges with a
/// negative cotangent weight.
pub fn minimal_surface(
    mesh: &Mesh,
    weights: TutteWeights,
) -> Result<(Vec<[f64; 3]>, usize), NodeError> {
    let topo = mesh.topology();
    if topo.boundary_loops.is_empty() {
        return Err(NodeError::topology(
            "mesh",
            "mesh is closed (no boundary loop); a minimal surface needs a fixed boundary",
        ));
    }
    if !topo.nonmanifold_edges.is_empty() {
        return Err(NodeError::topology(
            "mesh",
            format!(
                "mesh has {} edges with more than two faces; a manifold is needed",
                topo.nonmanifold_edges.len()
            ),
        ));
    }
    let tris = fan_triangles(mesh);
    let n = mesh.num_vertices();
    let mut fixed: Vec<Option<[f64; 3]>> = vec![None; n];
    let mut used = vec![false; n];
    for t in &tris {
        for &v in t {
            used[v as usize] = true;
        }
    }
    for v in 0..n {
        if !used[v] {
            fixed[v] = Some(mesh.positions[v]);
        }
    }
    for lp in &topo.boundary_loops {
        for &v in lp {
            fixed[v as usize] = Some(mesh.positions[v as usize]);
        }
    }
    let bad = |m: super::laplacian::LaplacianError| NodeError::invalid("mesh", m.to_string());
    let with_hint = |e: NodeError| {
        NodeError::new(
            e.kind,
            format!("{} (every connected component needs a boundary)", e.message),
        )
    };
    let (x, neg) = match weights {
        TutteWeights::Uniform | TutteWeights::Cotangent => {
            let rows = LaplacianRows::symmetric(
                &mesh.positions,
                &tris,
                weights == TutteWeights::Cotangent,
            )
            .map_err(bad)?;
            let order = rows.fill_reducing_order(&mesh.positions);
            let x = solve_dirichlet(rows.laplace(), &fixed, order.as_ref()).map_err(with_hint)?;
            let neg = if weights == TutteWeights::Cotangent {
                rows.negative_edges()
            } else {
                0
            };
            (x, neg)
        }
        TutteWeights::MeanValue => {
            let w = mean_value_weights(&mesh.positions, &tris).map_err(bad)?;
            (
                solve_dirichlet_weights(&w, &fixed, false).map_err(with_hint)?,
                0,
            )
        }
    };
    Ok((x, neg))
}

/// The weights the `weights` socket of `minimal_surface` accepts (Tutte's without mean value).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct SurfaceWeights(TutteWeights);

impl Choice for SurfaceWeights {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("uniform", SurfaceWeights(TutteWeights::Uniform)),
        ("cotangent", SurfaceWeights(TutteWeights::Cotangent)),
    ];
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Minimal surface: interior vertices from the Laplace equation, boundary fixed at its own positions.");
    b.add_input::<Mesh>("mesh");
    b.add_choice::<SurfaceWeights>("weights")
        .doc("uniform (membrane) or cotangent weights of the input geometry.");
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let SurfaceWeights(w) = ctx.choice::<SurfaceWeights>("weights")?;
    let (x, neg) = minimal_surface(&mesh, w)?;
    if w == TutteWeights::Cotangent {
        ctx.log(format!(
            "{neg} edges with negative cotangent weight (obtuse triangles)"
        ));
    }
    let mut out = (*mesh).clone();
    out.positions = x;
    out.normals = None;
    ctx.set_output("mesh", out);
    Ok(())
}

/// Registers `minimal_surface`.
pub fn register(r: &mut Registry) {
    r.add("minimal_surface", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::super::triangles::grid_triangles;
    use super::*;

    #[test]
    fn bumpy_disk_with_planar_boundary_becomes_planar() {
        // a grid disk on z = x + 2y with interior vertices lifted: the solution is planar again
        let n = 8;
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                let inner = i > 0 && j > 0 && i < n && j < n;
                let bump = if inner {
                    ((i * 7 + j * 3) % 5) as f64 * 0.1
                } else {
                    0.0
                };
                p.push([x, y, x + 2.0 * y + bump]);
            }
        }
        let m = Mesh::from_triangles(p, &grid_triangles(n, n)).unwrap();
        for w in [TutteWeights::Uniform, TutteWeights::Cotangent] {
            let (x, _) = minimal_surface(&m, w).unwrap();
            for q in &x {
                assert!((q[2] - q[0] - 2.0 * q[1]).abs() < 1e-10, "{w:?} {q:?}");
            }
        }
    }
}
