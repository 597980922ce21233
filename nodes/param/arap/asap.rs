//! `asap`: as-similar-as-possible parameterization in one linear solve (Liu et al. 2008 §4.2;
//! the same minimizer as LSCM, Lévy et al. 2002).
//!
//! With similarity targets the local step is linear in the UVs, so the local/global
//! iteration collapses to one quadratic: `E(u) = Σ_t A_t |J_t - S(J_t)|² = Σ_t 2 A_t (F_t² + G_t²)`,
//! where `(F, G)` is the anti-similarity part of `J` (see `frames::similarity_parts`). Two
//! vertices are pinned to fix the similarity; the rest comes from one sparse Cholesky solve.

use super::error::ArapError;
use super::frames::{local_step, similarity_parts, TriangleFrames, PAR_CHUNK};
use super::injective::orientation_and_flips;
use super::system::free_rows;
use super::{component_of, uv_outputs};
use cgnodes_api::prelude::*;
use cgnodes_linalg::SpdFactor;
use faer::sparse::Triplet;
use faer::{Mat, Par};
use rayon::prelude::*;
use std::time::Instant;

/// What `asap_parameterize` returns.
#[derive(Clone, Debug)]
pub struct AsapResult {
    /// One UV per vertex.
    pub uv: Vec<[f64; 2]>,
    /// The two pinned vertices.
    pub pins: [usize; 2],
    /// `Σ A |J - S(J)|² / Σ A`, the minimized (conformal) energy.
    pub energy: f64,
    /// ARAP energy of the result, `Σ A ((σ1-1)² + (σ2-1)²) / Σ A`.
    pub arap_energy: f64,
    /// Triangles whose orientation disagrees with the majority.
    pub flips: usize,
    /// Time taken, in milliseconds.
    pub elapsed_ms: f64,
}

/// ASAP parameterization of a connected triangle mesh. `pins`: the two vertices fixed to fix
/// the similarity (default: two far-apart vertices), placed at `(0, 0)` and `(|p_b - p_a|, 0)`
/// so that the result keeps the mesh's size along that chord.
pub fn asap_parameterize(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    pins: Option<[usize; 2]>,
) -> Result<AsapResult, ArapError> {
    let start = Instant::now();
    let n = positions.len();
    if triangles.is_empty() {
        return Err(ArapError::NoTriangles);
    }
    let frames = TriangleFrames::new(positions, triangles)?;
    let (comp, ncomp) = component_of(n, triangles);
    if ncomp != 1 {
        return Err(ArapError::Components(ncomp));
    }
    let used: Vec<bool> = comp.iter().map(|&c| c != u32::MAX).collect();
    let [a, b] = choose_pins(positions, &used, pins)?;
    let mut uv = vec![[0.0; 2]; n];
    uv[b] = [dist2(positions[a], positions[b]).sqrt(), 0.0];
    let mut fixed: Vec<bool> = used.iter().map(|u| !u).collect();
    fixed[a] = true;
    fixed[b] = true;
    let (free_index, free_vertices) = free_rows(&fixed);
    let nf = free_vertices.len();
    if nf > 0 {
        let (trip, mut rhs) = asap_system(&frames, &free_index, nf, &uv);
        let factor = SpdFactor::new(2 * nf, &trip, Par::Seq).map_err(ArapError::SingularAsap)?;
        factor.solve_in_place(rhs.as_mut());
        for v in 0..n {
            if free_index[v] != u32::MAX {
                let i = 2 * free_index[v] as usize;
                uv[v] = [rhs[(i, 0)], rhs[(i + 1, 0)]];
            }
        }
    }
    let (energy, arap_energy) = energies(&frames, &uv);
    let (_, flips) = orientation_and_flips(&frames, &uv);
    Ok(AsapResult {
        uv,
        pins: [a, b],
        energy,
        arap_energy,
        flips,
        elapsed_ms: start.elapsed().as_secs_f64() * 1e3,
    })
}

/// The two pinned vertices: `pins` checked (two different vertices of the triangles, `used`),
/// or by default a vertex farthest from the first used vertex and a vertex farthest from it
/// (two far-apart vertices, so the similarity is well fixed).
fn choose_pins(
    positions: &[[f64; 3]],
    used: &[bool],
    pins: Option<[usize; 2]>,
) -> Result<[usize; 2], ArapError> {
    let n = positions.len();
    if let Some([a, b]) = pins {
        if a >= n || b >= n || a == b || !used[a] || !used[b] {
            return Err(ArapError::Pins);
        }
        return Ok([a, b]);
    }
    let far = |from: usize| {
        (0..n)
            .filter(|&v| used[v])
            .max_by(|&x, &y| {
                dist2(positions[x], positions[from])
                    .total_cmp(&dist2(positions[y], positions[from]))
            })
            .unwrap_or(from)
    };
    let v0 = (0..n).find(|&v| used[v]).unwrap_or(0);
    let a = far(v0);
    Ok([a, far(a)])
}

/// The `2nf x 2nf` ASAP system over the free vertices (`free_index`: a vertex's row, or
/// `u32::MAX` when pinned; unknowns interleaved `(u, v)` per vertex): its lower triangle as
/// triplets, and the right-hand side that moves the pinned vertices' terms (at `uv`) over.
fn asap_system(
    frames: &TriangleFrames,
    free_index: &[u32],
    nf: usize,
    uv: &[[f64; 2]],
) -> (Vec<Triplet<usize, usize, f64>>, Mat<f64>) {
    let mut trip: Vec<Triplet<usize, usize, f64>> = Vec::with_capacity(21 * frames.len());
    let mut rhs = Mat::<f64>::zeros(2 * nf, 1);
    for t in 0..frames.len() {
        let (f, g) = anti_similarity_rows(frames, t);
        let w = 2.0 * frames.area[t];
        let tri = frames.triangles[t];
        // local unknown l: coordinate l / 3 of corner l % 3
        let var = |l: usize| -> (usize, usize) { (tri[l % 3] as usize, l / 3) };
        for l1 in 0..6 {
            let (v1, c1) = var(l1);
            let i1 = free_index[v1];
            if i1 == u32::MAX {
                continue;
            }
            let row = 2 * i1 as usize + c1;
            for l2 in 0..6 {
                let qv = w * (f[l1] * f[l2] + g[l1] * g[l2]);
                let (v2, c2) = var(l2);
                let i2 = free_index[v2];
                if i2 == u32::MAX {
                    rhs[(row, 0)] -= qv * uv[v2][c2];
                } else {
                    let col = 2 * i2 as usize + c2;
                    if col <= row {
                        trip.push(Triplet::new(row, col, qv));
                    }
                }
            }
        }
    }
    (trip, rhs)
}

/// Triangle `t`'s anti-similarity part of `J` as two rows `f`, `g` over its unknowns
/// `(x0, x1, x2, y0, y1, y2)`: `F = f·u`, `G = g·u`, so its energy block is
/// `2A (f fᵀ + g gᵀ)`. J's rows are `(g1·x, g2·x)` and `(g1·y, g2·y)` with `g1 = (-p, p, 0)`,
/// `g2 = (-q-r, q, r)` from `[x1-x0, x2-x0]⁻¹ = [[p, q], [0, r]]`.
fn anti_similarity_rows(frames: &TriangleFrames, t: usize) -> ([f64; 6], [f64; 6]) {
    let [p, q, r] = frames.inv_edges[t];
    let g1 = [-p, p, 0.0];
    let g2 = [-q - r, q, r];
    let f = [
        0.5 * g1[0],
        0.5 * g1[1],
        0.5 * g1[2],
        -0.5 * g2[0],
        -0.5 * g2[1],
        -0.5 * g2[2],
    ];
    let g = [
        0.5 * g2[0],
        0.5 * g2[1],
        0.5 * g2[2],
        0.5 * g1[0],
        0.5 * g1[1],
        0.5 * g1[2],
    ];
    (f, g)
}

/// The ASAP (conformal) and ARAP energies of `uv`, each as an area-weighted mean.
pub fn energies(frames: &TriangleFrames, uv: &[[f64; 2]]) -> (f64, f64) {
    let (conf, arap) = (0..frames.len())
        .into_par_iter()
        .with_min_len(PAR_CHUNK)
        .map(|t| {
            let j = frames.jacobian(t, uv);
            let (_, _, f, g) = similarity_parts(&j);
            let (_, e) = local_step(&j, None);
            (frames.area[t] * 2.0 * (f * f + g * g), frames.area[t] * e)
        })
        .reduce(|| (0.0, 0.0), |x, y| (x.0 + y.0, x.1 + y.1));
    (conf / frames.total_area, arap / frames.total_area)
}

fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
}

fn declare(b: &mut NodeBuilder) {
    b.doc("ASAP parameterization (Liu et al. 2008): similarity per triangle, one linear solve.");
    b.add_input::<Mesh>("mesh")
        .doc("Connected mesh to flatten (triangulated if needed).");
    b.add_input::<bool>("normalize")
        .default(true)
        .doc("Scale and move the UVs into [0,1]² (same scale on both axes); `flat` keeps the solved size.");
    b.add_output::<Mesh>("mesh")
        .doc("The input mesh with per-vertex UVs.");
    b.add_output::<Mesh>("flat")
        .doc("The flattened mesh (UV, 0).");
    b.add_output::<Table>("log")
        .doc("One row: energy (conformal), arap_energy, flips, elapsed_ms.");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let normalize: bool = ctx.input("normalize")?;
    let tri_mesh = mesh.triangulated();
    let triangles = tri_mesh
        .triangles()
        .ok_or_else(|| NodeError::invalid("mesh", "could not triangulate the mesh"))?;
    let res = asap_parameterize(&tri_mesh.positions, &triangles, None)?;
    let mut table = Table::from_row(&[
        ("energy", res.energy),
        ("arap_energy", res.arap_energy),
        ("flips", res.flips as f64),
        ("elapsed_ms", res.elapsed_ms),
    ]);
    table
        .meta
        .insert("pins".into(), format!("{} {}", res.pins[0], res.pins[1]));
    ctx.log(format!(
        "ASAP: conformal energy {:.4e}, ARAP energy {:.4e}, {} flipped triangles",
        res.energy, res.arap_energy, res.flips
    ));
    let (out, flat) = uv_outputs(&mesh, &tri_mesh, &res.uv, normalize);
    ctx.set_output("mesh", out);
    ctx.set_output("flat", flat);
    ctx.set_output("log", table);
    Ok(())
}

/// Registers `asap`.
pub fn register(r: &mut Registry) {
    r.add("asap", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::super::local_global::tests::planar_grid;
    use super::*;

    #[test]
    fn planar_mesh_is_reproduced_up_to_a_similarity() {
        let (p, t) = planar_grid(7);
        let r = asap_parameterize(&p, &t, Some([3, 40])).unwrap();
        // the similarity z -> s z + c (complex numbers) fitted through the pins
        let z = |q: [f64; 3]| (q[0], q[1]);
        let (pa, pb) = (z(p[3]), z(p[40]));
        let (ua, ub) = ((r.uv[3][0], r.uv[3][1]), (r.uv[40][0], r.uv[40][1]));
        let (dx, dy) = (pb.0 - pa.0, pb.1 - pa.1);
        let (ex, ey) = (ub.0 - ua.0, ub.1 - ua.1);
        let den = dx * dx + dy * dy;
        let s = ((ex * dx + ey * dy) / den, (ey * dx - ex * dy) / den);
        for (v, q) in p.iter().enumerate() {
            let (x, y) = (q[0] - pa.0, q[1] - pa.1);
            let pred = (ua.0 + s.0 * x - s.1 * y, ua.1 + s.1 * x + s.0 * y);
            assert!((pred.0 - r.uv[v][0]).abs() < 1e-10 && (pred.1 - r.uv[v][1]).abs() < 1e-10);
        }
        assert!(r.energy < 1e-20);
        // pins at chord length: a rigid motion, so the ARAP energy vanishes too
        assert!(r.arap_energy < 1e-18, "{}", r.arap_energy);
        assert_eq!(r.flips, 0);
    }

    #[test]
    fn result_minimizes_the_energy_for_its_pins() {
        let (mut p, t) = planar_grid(6);
        for (i, q) in p.iter_mut().enumerate() {
            q[2] = 0.3 * (q[0] * 3.0).sin() * (q[1] * 2.0).cos() + 0.01 * (i % 3) as f64;
        }
        let r = asap_parameterize(&p, &t, None).unwrap();
        let f = TriangleFrames::new(&p, &t).unwrap();
        assert!((energies(&f, &r.uv).0 - r.energy).abs() < 1e-14);
        assert!(
            r.energy > 1e-6,
            "a curved mesh is not flattened conformally"
        );
        // any move of the free vertices raises the energy (convex quadratic at its minimum)
        for k in 1..20 {
            let mut uv = r.uv.clone();
            for (v, w) in uv.iter_mut().enumerate() {
                if v != r.pins[0] && v != r.pins[1] {
                    let h = ((v * 31 + k * 17) % 13) as f64 / 13.0 - 0.5;
                    w[0] += 1e-3 * h;
                    w[1] -= 1e-3 * h * (k as f64 * 0.3).cos();
                }
            }
            assert!(energies(&f, &uv).0 > r.energy);
        }
    }
}
