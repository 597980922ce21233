//! `arap_parameterize`: the local/global parameterization of Liu et al. 2008 ("A
//! Local/Global Approach to Mesh Parameterization"), ARAP or the hybrid model, with an
//! optional fold-free line search (Smith & Schaefer 2015).
//!
//! Each iteration fits a target per triangle to the current Jacobian (local step: closed-form
//! 2x2 decomposition, in parallel, `energy::evaluate`), then solves for the UVs that best follow the
//! targets (global step: the cotangent Laplacian, factored once, both coordinates in one
//! solve; `system`). In fold-free mode the move towards the global solution is cut to the
//! largest step that keeps every triangle's orientation (`line_search`), then backed off until
//! the energy drops (Armijo); triangles that block the step are stiffened (`fold_free`). The
//! loop itself is `solver::iterate`.

use super::energy::ArapResult;
use super::error::ArapError;
use super::options::ArapOptions;
use super::prepared::ArapSystem;
use super::solver::iterate;

/// ARAP (or hybrid) parameterization of a triangle mesh from initial UVs, libigl style.
///
/// The energy is `Σ_t A_t |J_t - L_t|²`, which equals Liu et al.'s
/// `½ Σ_t Σ_(i,j) cot θ_ij |(u_i - u_j) - L_t (x_i - x_j)|²` (eq. 3). The global step solves
/// `Δ u = b` (eq. 6) with the cotangent Laplacian `Δ` restricted to the free vertices, factored
/// once. Energy never increases: the global step minimizes a convex quadratic in the UVs whose
/// value at the current UVs is the current energy, so every step length in `(0, 1]` along it
/// lowers it; the Armijo test only guards against rounding.
pub fn arap_parameterize(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    init_uv: &[[f64; 2]],
    opts: &ArapOptions,
) -> Result<ArapResult, ArapError> {
    // The loop runs several short parallel passes per iteration. Run from a thread outside
    // rayon's pool, each pass is injected into the pool and waited for, a round trip through
    // the OS per pass; on a pool thread the passes are split in place (timings: docs/arap.md).
    arap_parameterize_progress(positions, triangles, init_uv, opts, &|_| {})
}

/// `arap_parameterize` reporting the fraction of `opts.iterations` done after each iteration
/// (for progress bars).
pub fn arap_parameterize_progress(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    init_uv: &[[f64; 2]],
    opts: &ArapOptions,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<ArapResult, ArapError> {
    rayon::scope(|_| {
        let system = ArapSystem::new(positions, triangles, opts)?;
        iterate(system, init_uv, opts, progress)
    })
}

/// `arap_parameterize_progress` on a system built already (`ArapSystem::new` with the same
/// `opts.pin` and `opts.injective`, else `ArapError::SystemOptions`): the factorization can
/// then run while the initial UVs are computed.
pub fn arap_parameterize_prepared(
    system: ArapSystem,
    init_uv: &[[f64; 2]],
    opts: &ArapOptions,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<ArapResult, ArapError> {
    rayon::scope(|_| iterate(system, init_uv, opts, progress))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::arap::frames::TriangleFrames;
    use cgnodes_api::prelude::{ErrorKind, NodeError};

    /// A wavy-free planar disk: a triangulated regular grid in the plane z = 0.
    pub(crate) fn planar_grid(k: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let mut p = Vec::new();
        for j in 0..=k {
            for i in 0..=k {
                let (x, y) = (i as f64 / k as f64, j as f64 / k as f64);
                // irregular but planar: shift interior points a little
                let s = if i > 0 && i < k && j > 0 && j < k {
                    0.2 / k as f64
                } else {
                    0.0
                };
                p.push([x + s * ((i * 7 + j * 3) % 5) as f64 / 5.0, y, 0.0]);
            }
        }
        (p, crate::triangles::grid_triangles(k, k))
    }

    #[test]
    fn planar_mesh_comes_back_rigidly() {
        let (p, t) = planar_grid(8);
        // start from an anisotropic, rotated, fold-free squash of the true layout
        let init: Vec<[f64; 2]> = p
            .iter()
            .map(|q| {
                [
                    0.3 * q[0] + 0.1 * q[1],
                    -0.2 * q[0] + 1.7 * q[1] + 0.05 * q[0] * q[0],
                ]
            })
            .collect();
        for injective in [false, true] {
            let opts = ArapOptions {
                iterations: 500,
                tolerance: 0.0,
                injective,
                ..Default::default()
            };
            let r = arap_parameterize(&p, &t, &init, &opts).unwrap();
            assert!(r.energy < 1e-16, "energy {}", r.energy);
            // all pairwise distances preserved: a rigid motion
            let d =
                |a: [f64; 2], b: [f64; 2]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
            let d3 =
                |a: [f64; 3], b: [f64; 3]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
            for i in (0..p.len()).step_by(7) {
                for j in (0..p.len()).step_by(5) {
                    assert!((d(r.uv[i], r.uv[j]) - d3(p[i], p[j])).abs() < 1e-7);
                }
            }
            assert_eq!(r.flips, 0);
        }
    }

    /// A system built apart gives the same run, bit for bit, and one built for another pin
    /// or mode is refused.
    #[test]
    fn prepared_system_runs_like_the_whole_call() {
        let (p, t) = planar_grid(6);
        let init: Vec<[f64; 2]> = p.iter().map(|q| [0.4 * q[0], q[1] + 0.1 * q[0]]).collect();
        let opts = ArapOptions {
            iterations: 30,
            ..Default::default()
        };
        let whole = arap_parameterize(&p, &t, &init, &opts).unwrap();
        let system = ArapSystem::new(&p, &t, &opts).unwrap();
        let apart = arap_parameterize_prepared(system, &init, &opts, &|_| {}).unwrap();
        assert_eq!(whole.uv, apart.uv);
        assert_eq!(whole.energy, apart.energy);
        for other in [
            ArapOptions {
                pin: Some(3),
                ..opts.clone()
            },
            ArapOptions {
                injective: !opts.injective,
                ..opts.clone()
            },
        ] {
            let system = ArapSystem::new(&p, &t, &opts).unwrap();
            let e = arap_parameterize_prepared(system, &init, &other, &|_| {}).unwrap_err();
            assert_eq!(e, ArapError::SystemOptions);
        }
    }

    #[test]
    fn clockwise_start_is_mirrored_and_restored() {
        let (p, t) = planar_grid(4);
        let init: Vec<[f64; 2]> = p.iter().map(|q| [q[0] * 0.5, -q[1]]).collect();
        let r = arap_parameterize(&p, &t, &init, &ArapOptions::default()).unwrap();
        let f = TriangleFrames::new(&p, &t).unwrap();
        // still clockwise, and rigid
        assert!((0..t.len()).all(|k| f.signed_area2(k, &r.uv) < 0.0));
        assert!(r.energy < 1e-10);
    }

    #[test]
    fn refuses_folded_start_in_fold_free_mode() {
        let (p, t) = planar_grid(3);
        let mut init: Vec<[f64; 2]> = p.iter().map(|q| [q[0], q[1]]).collect();
        init[5] = [2.0, 2.0];
        let e = arap_parameterize(&p, &t, &init, &ArapOptions::default()).unwrap_err();
        assert!(matches!(e, ArapError::FoldedStart(_)), "{e}");
        assert_eq!(NodeError::from(e).kind, ErrorKind::Folded);
        let opts = ArapOptions {
            injective: false,
            ..Default::default()
        };
        assert!(arap_parameterize(&p, &t, &init, &opts).is_ok());
        let bad = ArapOptions {
            pin: Some(1000),
            ..Default::default()
        };
        assert_eq!(
            arap_parameterize(&p, &t, &init, &bad).unwrap_err(),
            ArapError::Pin {
                pin: 1000,
                vertices: 16
            }
        );
    }

    #[test]
    fn hybrid_on_planar_mesh_reaches_zero_energy() {
        let (p, t) = planar_grid(5);
        let init: Vec<[f64; 2]> = p.iter().map(|q| [0.5 * q[0], 0.7 * q[1]]).collect();
        let opts = ArapOptions {
            iterations: 500,
            tolerance: 0.0,
            lambda: Some(2.0),
            ..Default::default()
        };
        let r = arap_parameterize(&p, &t, &init, &opts).unwrap();
        assert!(r.energy < 1e-14, "{}", r.energy);
    }
}
