//! `ArapSystem`: what `arap_parameterize` builds before it looks at the initial UVs (the
//! triangles' frames, the pinned vertices, the cotangent Laplacian on the free vertices and
//! its factor). Built apart, it can be factored while the initial UVs are computed: the `arap`
//! node builds it on one core while Tutte's start runs on the other.

use super::error::ArapError;
use super::frames::TriangleFrames;
use super::options::ArapOptions;
use super::system::{
    corner_weights, elimination_rows, fixed_vertices, free_rows, laplacian_triplets,
};
use cgnodes_linalg::SpdFactor;
use faer::sparse::Triplet;
use faer::Par;

/// Free vertices from which the fold-free mode, which refactors the Laplacian up to once per
/// iteration, asks for a supernodal factor (`SpdFactor::new_supernodal`). 20 fold-free
/// iterations on bunny_base4 (10k vertices), ms per iteration: 8.63 with faer's choice
/// (simplicial) against 6.43 supernodal, the same 12 refactorizations and energy; on
/// bunny_base (2.5k) 1.00 simplicial against 1.18; from about 40k faer picks supernodal.
const SUPERNODAL_MIN: usize = 5000;

/// The UV-independent part of an ARAP run (Liu et al. 2008, eq. 6: the global step's
/// matrix): `ArapSystem::new`, then `arap_parameterize_prepared`.
pub struct ArapSystem {
    /// Number of mesh vertices.
    pub(super) n: usize,
    /// The triangles' frames and cotangents.
    pub(super) frames: TriangleFrames,
    /// Cotangent Laplacian on the free vertices (lower triangle), each entry tagged with its
    /// triangle (`trip_tri`) so that the fold-free mode can reweight triangles.
    pub(super) trip: Vec<Triplet<usize, usize, f64>>,
    pub(super) trip_tri: Vec<u32>,
    /// `None` when no vertex is free.
    pub(super) factor: Option<SpdFactor>,
    /// Each vertex's row in the factor's elimination order (`u32::MAX` when fixed).
    pub(super) row_of: Vec<u32>,
    /// The vertex of each row.
    pub(super) row_vertex: Vec<usize>,
    /// Right-hand side weights per corner (`corner_weights`).
    pub(super) corner_w: Vec<[[f64; 2]; 3]>,
    /// The options it was built for: its pinned vertices and factor kind depend on them.
    pin: Option<usize>,
    injective: bool,
}

impl ArapSystem {
    /// Checks the mesh and `opts.pin`, pins one vertex per connected component (`opts.pin`
    /// in its own) and factors the cotangent Laplacian on the other vertices.
    pub fn new(
        positions: &[[f64; 3]],
        triangles: &[[u32; 3]],
        opts: &ArapOptions,
    ) -> Result<ArapSystem, ArapError> {
        let n = positions.len();
        if triangles.is_empty() {
            return Err(ArapError::NoTriangles);
        }
        if let Some(p) = opts.pin.filter(|&p| p >= n) {
            return Err(ArapError::Pin {
                pin: p,
                vertices: n,
            });
        }
        let frames = TriangleFrames::new(positions, triangles)?;
        // Fixed vertices: one pin per connected component, and vertices in no triangle.
        let fixed = fixed_vertices(n, triangles, opts.pin);
        let (free_index, free_vertices) = free_rows(&fixed);
        let nf = free_vertices.len();
        let (trip, trip_tri) = laplacian_triplets(&frames, &free_index);
        let factor = if nf > 0 {
            let mut f = if opts.injective && nf >= SUPERNODAL_MIN {
                SpdFactor::new_supernodal(nf, &trip, Par::Seq)
            } else {
                SpdFactor::new(nf, &trip, Par::Seq)
            }
            .map_err(ArapError::SingularLaplacian)?;
            f.prepare_many_solves();
            Some(f)
        } else {
            None
        };
        let (row_of, row_vertex) = factor.as_ref().map_or((Vec::new(), Vec::new()), |f| {
            elimination_rows(f, &free_index)
        });
        let corner_w = corner_weights(&frames);
        Ok(ArapSystem {
            n,
            frames,
            trip,
            trip_tri,
            factor,
            row_of,
            row_vertex,
            corner_w,
            pin: opts.pin,
            injective: opts.injective,
        })
    }

    /// Whether this system serves a run with `opts` (same pin and mode).
    pub(super) fn fits(&self, opts: &ArapOptions) -> bool {
        self.pin == opts.pin && self.injective == opts.injective
    }
}
