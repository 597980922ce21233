//! Boundary particles for the simulation box (Akinci et al. 2012, "Versatile Rigid-Fluid
//! Coupling for Incompressible SPH", ACM TOG 31(4)): the walls are sampled with static
//! particles outside the box, in layers thick enough to cover the support radius, on a
//! lattice that continues the fluid's, and each gets the volume of eq. (4) over that
//! lattice, so that a fluid particle at rest next to a wall sees the rest density.
//! Boundary particles contribute `rho0 V_b W_ib` to density and mirror the fluid
//! particle's pressure (`p_b = p_i`) in the pressure force.

use super::kernel::CubicSpline;

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

/// The volume of a boundary particle: Akinci et al. 2012 eq. (4),
/// `V_b = 1 / sum_k W(x_b - x_k)`, evaluated over the full lattice the walls are cut from.
/// Evaluating it over the sampled wall particles only (as Akinci do for one-layer walls)
/// misses the fluid side of the inner layer, inflates `V_b` and makes the fluid next to a
/// thick lattice wall read too high a density, which pushes the first fluid layer off the
/// floor; the full-lattice sum makes a fluid lattice at rest read exactly `rho0` there.
pub fn lattice_volume(spacing: [f64; 3], kernel: &CubicSpline, dim: usize) -> f64 {
    let h = kernel.h;
    let m = |a: usize| {
        if a < dim {
            (h / spacing[a]).ceil() as i64
        } else {
            0
        }
    };
    let mut s = 0.0;
    for k in -m(2)..=m(2) {
        for j in -m(1)..=m(1) {
            for i in -m(0)..=m(0) {
                let d = [
                    i as f64 * spacing[0],
                    j as f64 * spacing[1],
                    k as f64 * spacing[2],
                ];
                s += kernel.w((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
            }
        }
    }
    1.0 / s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shell_count_and_volume() {
        let pts = box_particles([0.0; 3], [1.0, 0.5, 0.0], 0.1, 2, 2);
        // (10 + 4) x (5 + 4) lattice minus the 10 x 5 interior.
        assert_eq!(pts.len(), 14 * 9 - 50);
        // The cubic spline with support 2s sums to ~1/s^2 over a square lattice (Riemann sum
        // of a unit integral).
        let kern = CubicSpline::new(0.2, 2);
        let v = lattice_volume([0.1; 3], &kern, 2);
        assert!((v / 0.01 - 1.0).abs() < 0.01, "{v}");
    }
}
