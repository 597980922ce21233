//! Boundary particles for the simulation box (Akinci et al. 2012, "Versatile Rigid-Fluid
//! Coupling for Incompressible SPH", ACM TOG 31(4)): the walls are sampled with static
//! particles outside the box, continuing the fluid lattice, and each gets the volume
//! `V_b = 1 / sum_k W(x_b - x_k)` over its boundary neighbours (eq. 4), so that a fluid
//! particle at rest next to a wall sees the rest density however the wall is sampled.
//! Boundary particles contribute `rho0 V_b W_ib` to density and mirror the fluid
//! particle's pressure (`p_b = p_i`) in the pressure force.

use super::grid::Grid;
use super::kernel::CubicSpline;
use rayon::prelude::*;

/// Samples `layers` layers of particles outside the box `[min, max]` (on the first `dim`
/// axes; z = 0 in 2-D), with spacing close to `spacing` chosen so the box size is a whole
/// number of spacings on each axis. Positions are the centres of the lattice cells
/// `min + (i + 1/2) s` for `i` in `-layers..0` and `n..n + layers`.
pub fn box_particles(
    min: [f64; 3],
    max: [f64; 3],
    spacing: f64,
    layers: usize,
    dim: usize,
) -> Vec<[f64; 3]> {
    let mut n = [1i64; 3];
    let mut s = [spacing; 3];
    for a in 0..dim {
        n[a] = ((max[a] - min[a]) / spacing).round().max(1.0) as i64;
        s[a] = (max[a] - min[a]) / n[a] as f64;
    }
    let l = layers as i64;
    let range = |a: usize| if a < dim { -l..n[a] + l } else { 0..1 };
    let mut out = Vec::new();
    for k in range(2) {
        for j in range(1) {
            for i in range(0) {
                let idx = [i, j, k];
                let outside = (0..dim).any(|a| idx[a] < 0 || idx[a] >= n[a]);
                if !outside {
                    continue;
                }
                let mut p = [0.0; 3];
                for a in 0..dim {
                    p[a] = min[a] + (idx[a] as f64 + 0.5) * s[a];
                }
                out.push(p);
            }
        }
    }
    out
}

/// Akinci et al. 2012 eq. (4): `V_b = 1 / sum_k W(x_b - x_k)` over the boundary particles
/// `k` (including `b` itself).
pub fn volumes(points: &[[f64; 3]], grid: &Grid, kernel: &CubicSpline) -> Vec<f64> {
    points
        .par_iter()
        .map(|p| {
            let mut s = 0.0;
            grid.for_each_candidate(p, |j| {
                let q = points[j];
                let r = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2))
                    .sqrt();
                s += kernel.w(r);
            });
            1.0 / s
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shell_count_and_volume() {
        let pts = box_particles([0.0; 3], [1.0, 0.5, 0.0], 0.1, 2, 2);
        // (10 + 4) x (5 + 4) lattice minus the 10 x 5 interior.
        assert_eq!(pts.len(), 14 * 9 - 50);
        let kern = CubicSpline::new(0.2, 2);
        let g = Grid::build(&pts, 0.2).unwrap();
        let v = volumes(&pts, &g, &kern);
        // Deep inside a 2-layer wall the volume is close to the lattice cell area s^2; at the
        // inner face (half the neighbours missing) it is larger (Akinci's compensation).
        let inner = pts
            .iter()
            .position(|p| (p[0] - 0.45).abs() < 1e-9 && (p[1] + 0.05).abs() < 1e-9)
            .unwrap();
        assert!(v[inner] > 0.01 && v[inner] < 0.02, "{}", v[inner]);
    }
}
