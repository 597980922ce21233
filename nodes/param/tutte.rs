//! `tutte`: Tutte's embedding of a disk mesh into the plane (Tutte 1963; Floater 1997, 2003).
//!
//! The boundary loop goes to a convex shape (`boundary_map`); every interior vertex is a convex
//! combination of its neighbours, `sum_j w_ij (u_i - u_j) = 0`, solved for the interior only with
//! the boundary moved to the right-hand side. With positive weights (uniform, Floater's mean
//! value) the result has no flipped triangle (Tutte's theorem, Floater 2003 Thm 1). Cotangent
//! weights (the discrete harmonic map, Pinkall and Polthier 1993; Eck et al. 1995) turn negative
//! on obtuse triangles and then lose that guarantee; their count is logged.
//!
//! Meshes with several boundary loops but genus 0 (scanned surfaces with holes) can be mapped
//! with `holes: fill`: every loop but the longest is closed by a virtual vertex joined to the
//! loop by a fan of triangles, the resulting disk is mapped, and the virtual vertices are
//! dropped, which keeps the no-fold guarantee for the real triangles.

use super::boundary_map::{map_boundary, parse_start, rotate_loop, Spacing};
use super::laplacian::{mean_value_weights, LaplacianError};
use super::laplacian_rows::LaplacianRows;
use super::triangles::fan_triangles;
use super::uv_metrics::uv_metrics;
use cgnodes_api::prelude::*;
use cgnodes_linalg::laplace::DirichletFactor;
use cgnodes_linalg::laplace_weights::solve_dirichlet_weights;
use cgnodes_linalg::nested_dissection::Dissection;

pub use super::boundary_map::BoundaryShape;

/// The edge weights of the Tutte system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TutteWeights {
    /// Every neighbour counts the same (Tutte 1963): barycentric embedding.
    Uniform,
    /// Cotangent weights: the discrete harmonic map (Pinkall and Polthier 1993).
    Cotangent,
    /// Floater's mean-value weights (Floater 2003): positive and shape-preserving.
    MeanValue,
}

impl Choice for TutteWeights {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("uniform", Self::Uniform),
        ("cotangent", Self::Cotangent),
        ("mean_value", Self::MeanValue),
    ];
}

/// What `tutte` does with a mesh of several boundary loops (the `holes` socket).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Holes {
    /// Refuse it: Tutte's embedding needs a disk.
    Error,
    /// Close every loop but the longest with a virtual fan vertex first.
    Fill,
}

impl Choice for Holes {
    const CHOICES: &'static [(&'static str, Self)] =
        &[("error", Self::Error), ("fill", Self::Fill)];
}

/// Everything `tutte` can be told.
#[derive(Clone, Debug)]
pub struct TutteOptions {
    /// Edge weights.
    pub weights: TutteWeights,
    /// Shape the boundary is mapped to.
    pub boundary: BoundaryShape,
    /// Spacing of the boundary vertices along the shape.
    pub spacing: Spacing,
    /// Close every boundary loop but the longest with a virtual fan vertex first.
    pub fill_holes: bool,
    /// Boundary vertex placed at the shape's start point (default: the loop's first vertex).
    pub start_vertex: Option<u32>,
}

impl Default for TutteOptions {
    fn default() -> Self {
        TutteOptions {
            weights: TutteWeights::Uniform,
            boundary: BoundaryShape::Circle,
            spacing: Spacing::ArcLength,
            fill_holes: false,
            start_vertex: None,
        }
    }
}

/// The UVs and what happened on the way.
#[derive(Clone, Debug)]
pub struct TutteResult {
    /// One UV per vertex of the input mesh (vertices used by no face get (0, 0)).
    pub uvs: Vec<[f64; 2]>,
    /// Undirected edges with a negative cotangent weight (0 for the other weightings).
    pub negative_weights: usize,
    /// Boundary loops closed by a virtual vertex.
    pub filled_holes: usize,
    /// The boundary loop that was mapped, from its start vertex.
    pub boundary: Vec<u32>,
}

/// Per-vertex UVs of a disk mesh (triangulated implicitly); `fill_holes` closes all boundary
/// loops but the longest with virtual fan vertices first.
pub fn tutte_parameterize(
    mesh: &Mesh,
    weights: TutteWeights,
    boundary: BoundaryShape,
    fill_holes: bool,
) -> Result<Vec<[f64; 2]>, NodeError> {
    let opts = TutteOptions {
        weights,
        boundary,
        fill_holes,
        ..Default::default()
    };
    Ok(tutte(mesh, &opts)?.uvs)
}

/// Checks that `mesh` is a disk, or with `fill_holes` a genus-0 surface with holes, saying
/// what is wrong in the words of the Tutte node.
pub fn check_tutte_topology(mesh: &Mesh, fill_holes: bool) -> Result<(), NodeError> {
    let topo = mesh.topology();
    let err = |m: String| Err(NodeError::topology("mesh", m));
    if !topo.nonmanifold_edges.is_empty() || !topo.nonmanifold_vertices.is_empty() {
        return err(format!(
            "mesh is not manifold ({} edges with more than two faces, {} non-manifold vertices); Tutte needs a disk",
            topo.nonmanifold_edges.len(),
            topo.nonmanifold_vertices.len()
        ));
    }
    if !topo.misoriented_edges.is_empty() {
        return err(format!(
            "mesh faces are inconsistently oriented ({} edges); Tutte needs a disk",
            topo.misoriented_edges.len()
        ));
    }
    if topo.num_face_components() != 1 {
        return err(format!(
            "mesh has {} connected components; Tutte needs a disk",
            topo.num_face_components()
        ));
    }
    let b = topo.boundary_loops.len();
    if b == 0 {
        return err(
            "mesh is closed (no boundary loop); Tutte needs a disk: cut it open first".into(),
        );
    }
    if b > 1 && !fill_holes {
        return err(format!(
            "mesh has {b} boundary loops; Tutte needs a disk; use holes: fill"
        ));
    }
    // Filling b - 1 loops adds b - 1 to the Euler characteristic; a disk has 1.
    let chi = topo.euler_characteristic();
    if chi + b as i64 - 1 != 1 {
        let g2 = 2 - chi - b as i64;
        return err(format!(
            "mesh has Euler characteristic {chi} with {b} boundary loop(s), so genus {}; Tutte needs a disk (genus 0): cut it open first",
            if g2 >= 0 && g2 % 2 == 0 { format!("{}", g2 / 2) } else { "undefined".into() }
        ));
    }
    Ok(())
}

/// Tutte's embedding with all options; see the module documentation.
pub fn tutte(mesh: &Mesh, opts: &TutteOptions) -> Result<TutteResult, NodeError> {
    let n = mesh.num_vertices();
    let mut triangles = fan_triangles(mesh);
    // The symmetric system needs only the triangles: its weights, elimination order and
    // factorization (for the vertices on single-triangle edges held fixed, which is the
    // boundary loop of a disk) are built on one core while the connectivity is checked on the
    // other. Filled holes change the system; it is then built again below.
    let (checked, early) = rayon::join(
        || check_tutte_topology(mesh, opts.fill_holes),
        || {
            let (rows, order) = symmetric_rows(&mesh.positions, &triangles, opts.weights)?;
            let factor =
                DirichletFactor::new(rows.laplace(), &rows.boundary_or_unused(), order.as_ref());
            Ok::<_, LaplacianError>((rows, factor))
        },
    );
    checked?;
    let topo = mesh.topology();
    let mut positions = std::borrow::Cow::Borrowed(&mesh.positions);
    let loop_len = |lp: &[u32]| -> f64 {
        (0..lp.len())
            .map(|k| {
                let a = mesh.positions[lp[k] as usize];
                let b = mesh.positions[lp[(k + 1) % lp.len()] as usize];
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
            })
            .sum()
    };
    let loops = &topo.boundary_loops;
    let longest = (0..loops.len())
        .max_by(|&a, &b| loop_len(&loops[a]).total_cmp(&loop_len(&loops[b])))
        .unwrap_or(0);
    let mut filled = 0;
    for (k, lp) in loops.iter().enumerate() {
        if k == longest {
            continue;
        }
        // Virtual vertex at the loop's centroid; the fan runs against the loop's direction so
        // its triangles are oriented like their neighbours across the loop.
        let c = positions.len() as u32;
        let mut centroid = [0.0; 3];
        for &v in lp {
            for (c, x) in centroid.iter_mut().zip(mesh.positions[v as usize]) {
                *c += x / lp.len() as f64;
            }
        }
        positions.to_mut().push(centroid);
        for i in 0..lp.len() {
            triangles.push([lp[(i + 1) % lp.len()], lp[i], c]);
        }
        filled += 1;
    }
    let boundary = rotate_loop(&loops[longest], opts.start_vertex)?;
    let buv = map_boundary(&positions, &boundary, opts.boundary, opts.spacing)
        .map_err(|m| NodeError::topology("mesh", m))?;
    let mut fixed: Vec<Option<[f64; 2]>> = vec![None; positions.len()];
    let mut used = vec![false; positions.len()];
    for t in &triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    for (v, u) in used.iter().enumerate() {
        if !u {
            fixed[v] = Some([0.0, 0.0]);
        }
    }
    for (&v, uv) in boundary.iter().zip(&buv) {
        fixed[v as usize] = Some(*uv);
    }
    let bad = |m: LaplacianError| NodeError::invalid("mesh", m.to_string());
    let (mut uvs, negative) = if opts.weights == TutteWeights::MeanValue {
        let w = mean_value_weights(&positions, &triangles).map_err(bad)?;
        (solve_dirichlet_weights(&w, &fixed, false)?, 0)
    } else {
        let is_fixed: Vec<bool> = fixed.iter().map(Option::is_some).collect();
        let (rows, factor) = match early {
            Ok((rows, Ok(f))) if filled == 0 && f.fixes(&is_fixed) => (rows, f),
            _ => {
                let (rows, order) =
                    symmetric_rows(&positions, &triangles, opts.weights).map_err(bad)?;
                let f = DirichletFactor::new(rows.laplace(), &is_fixed, order.as_ref())?;
                (rows, f)
            }
        };
        let negative = if opts.weights == TutteWeights::Cotangent {
            rows.negative_edges()
        } else {
            0
        };
        (factor.solve(rows.laplace(), &fixed)?, negative)
    };
    uvs.truncate(n);
    Ok(TutteResult {
        uvs,
        negative_weights: negative,
        filled_holes: filled,
        boundary,
    })
}

/// The summed symmetric weights (uniform or cotangent) of `triangles` in rows and their
/// fill-reducing order; an error for mean-value weights, which are not symmetric.
#[allow(clippy::type_complexity)]
fn symmetric_rows(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    weights: TutteWeights,
) -> Result<(LaplacianRows, Option<Dissection>), LaplacianError> {
    if weights == TutteWeights::MeanValue {
        return Err(LaplacianError::NotSymmetric);
    }
    let rows = LaplacianRows::symmetric(positions, triangles, weights == TutteWeights::Cotangent)?;
    let order = rows.fill_reducing_order(positions);
    Ok((rows, order))
}

/// The mesh flattened onto its UVs: positions (u, v, 0), same faces, normals dropped.
pub fn flatten(mesh: &Mesh, uvs: &[[f64; 2]]) -> Mesh {
    let mut flat = mesh.clone();
    flat.positions = uvs.iter().map(|t| [t[0], t[1], 0.0]).collect();
    flat.normals = None;
    flat
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Tutte's embedding: boundary on a circle or square, interior as convex combinations of neighbours (uniform, cotangent or mean-value weights).");
    b.add_input::<Mesh>("mesh");
    b.add_choice::<TutteWeights>("weights").doc(
        "uniform (Tutte), cotangent (harmonic; may fold on obtuse meshes), mean_value (Floater).",
    );
    b.add_choice::<BoundaryShape>("boundary");
    b.add_choice::<Spacing>("spacing")
        .doc("Boundary vertex spacing.");
    b.add_choice::<Holes>("holes")
        .doc("fill: close all boundary loops but the longest with virtual fan vertices first.");
    b.add_input::<i64>("start_vertex")
        .default(-1i64)
        .doc("Boundary vertex at the start point; -1: the loop's first vertex.");
    b.add_output::<Mesh>("mesh")
        .doc("The input mesh with per-vertex UVs.");
    b.add_output::<Mesh>("flat")
        .doc("The mesh at its UVs, z = 0.");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let opts = TutteOptions {
        weights: ctx.choice::<TutteWeights>("weights")?,
        boundary: ctx.choice::<BoundaryShape>("boundary")?,
        spacing: ctx.choice::<Spacing>("spacing")?,
        fill_holes: ctx.choice::<Holes>("holes")? == Holes::Fill,
        start_vertex: parse_start(ctx.input("start_vertex")?),
    };
    let r = tutte(&mesh, &opts)?;
    if opts.weights == TutteWeights::Cotangent {
        ctx.log(format!(
            "{} edges with negative cotangent weight (obtuse triangles)",
            r.negative_weights
        ));
    }
    if r.filled_holes > 0 {
        ctx.log(format!(
            "{} holes filled with virtual fan vertices",
            r.filled_holes
        ));
    }
    let m = uv_metrics(&mesh.positions, &fan_triangles(&mesh), &r.uvs);
    ctx.log(format!(
        "{} flipped triangles, {} collapsed; angle distortion mean {:.4}",
        m.flipped, m.collapsed, m.angle_distortion_mean
    ));
    let mut out = (*mesh).clone();
    out.uvs = Some(Attribute {
        domain: Domain::Vertex,
        values: r.uvs.clone(),
    });
    let flat = flatten(&out, &r.uvs);
    ctx.set_output("mesh", out);
    ctx.set_output("flat", flat);
    Ok(())
}

/// Registers `tutte`.
pub fn register(r: &mut Registry) {
    r.add("tutte", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::super::triangles::grid_triangles_with;
    use super::*;

    /// A planar disk: centre, `rings` rings of `k` vertices each (inner rings jittered), the
    /// outer ring a regular k-gon on the circle the mapping uses.
    pub(crate) fn polar_disk(rings: usize, k: usize, jitter: f64) -> Mesh {
        let mut p = vec![[0.5, 0.5, 0.0]];
        for r in 1..=rings {
            for j in 0..k {
                let mut rad = 0.5 * r as f64 / rings as f64;
                let mut a = std::f64::consts::TAU * (j as f64 + 0.5 * (r % 2) as f64) / k as f64;
                if r < rings {
                    let h = ((r * 31 + j * 17) % 13) as f64 / 13.0 - 0.5;
                    rad *= 1.0 + jitter * h * 0.5;
                    a += jitter * h / k as f64;
                }
                p.push([0.5 + rad * a.cos(), 0.5 + rad * a.sin(), 0.0]);
            }
        }
        let id = |r: usize, j: usize| (1 + (r - 1) * k + j % k) as u32;
        let mut t: Vec<[u32; 3]> = (0..k).map(|j| [0, id(1, j), id(1, j + 1)]).collect();
        // ring r to r + 1 is a strip of squares: r along the grid's first axis
        t.extend(grid_triangles_with(rings - 1, k, |i, j| id(i + 1, j)));
        Mesh::from_triangles(p, &t).unwrap()
    }

    #[test]
    fn linear_precision_of_cotangent_and_mean_value() {
        let m = polar_disk(5, 16, 0.6);
        let lp = &m.topology().boundary_loops[0];
        for w in [TutteWeights::Cotangent, TutteWeights::MeanValue] {
            let start = lp[3];
            let opts = TutteOptions {
                weights: w,
                start_vertex: Some(start),
                ..Default::default()
            };
            let r = tutte(&m, &opts);
            let uv = r.unwrap().uvs;
            // boundary k-gon rotated to start at `start`: compare after aligning by the start
            let q = m.positions[start as usize];
            let rot = (q[1] - 0.5).atan2(q[0] - 0.5);
            let (c, s) = (rot.cos(), rot.sin());
            let mut err: f64 = 0.0;
            for (p, t) in m.positions.iter().zip(&uv) {
                let (x, y) = (t[0] - 0.5, t[1] - 0.5);
                let back = [0.5 + c * x - s * y, 0.5 + s * x + c * y];
                err = err.max((back[0] - p[0]).abs()).max((back[1] - p[1]).abs());
            }
            assert!(err < 1e-10, "{w:?}: {err}");
        }
    }

    #[test]
    fn uniform_weights_do_not_have_linear_precision() {
        // Sanity check that the test above can fail: uniform weights move jittered vertices.
        let m = polar_disk(5, 16, 0.6);
        let uv =
            tutte_parameterize(&m, TutteWeights::Uniform, BoundaryShape::Circle, false).unwrap();
        let moved = m
            .positions
            .iter()
            .zip(&uv)
            .map(|(p, t)| ((p[0] - 0.5).hypot(p[1] - 0.5) - (t[0] - 0.5).hypot(t[1] - 0.5)).abs())
            .fold(0.0, f64::max);
        assert!(moved > 1e-3);
    }

    #[test]
    fn refuses_closed_and_holed_meshes() {
        let p = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let tet = Mesh::from_triangles(p, &[[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]]).unwrap();
        let e = tutte_parameterize(&tet, TutteWeights::Uniform, BoundaryShape::Circle, true)
            .unwrap_err();
        assert_eq!(e.kind, ErrorKind::Topology);
        assert!(e.message.contains("closed"), "{}", e.message);
    }

    #[test]
    fn node_outputs_uv_mesh_and_flat_mesh() {
        let mut r = Registry::new();
        register(&mut r);
        let decl = r.get("tutte").unwrap();
        let mut inputs = std::collections::BTreeMap::new();
        inputs.insert("mesh".to_string(), Value::from(polar_disk(3, 8, 0.3)));
        inputs.insert("weights".to_string(), Value::from("mean_value"));
        let mut state = None;
        let files = FileEnv::default();
        let mut ctx = ExecContext::standalone(decl, inputs, &mut state, &files, 0);
        (decl.exec.as_ref().unwrap())(&mut ctx).unwrap();
        assert!(ctx.logs().iter().any(|l| l.contains("0 flipped")));
        let outs = ctx.take_outputs();
        let Some(Value::Mesh(m)) = outs.get("mesh") else {
            panic!("no mesh")
        };
        let Some(Value::Mesh(f)) = outs.get("flat") else {
            panic!("no flat")
        };
        let uv = m.vertex_uvs().unwrap();
        for (t, p) in uv.iter().zip(&f.positions) {
            assert_eq!([t[0], t[1], 0.0], *p);
        }
    }
}
