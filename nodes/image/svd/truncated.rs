//! The exact thin SVD A = U Σ V^T through faer (bidiagonalization and divide and conquer).

use super::{Factors, SvdError};
use faer::MatRef;

/// The thin SVD of `a` (r = min(m, n) singular triplets, values decreasing).
pub fn thin_svd(a: MatRef<'_, f64>) -> Result<Factors, SvdError> {
    if a.nrows() == 0 || a.ncols() == 0 {
        return Err(SvdError::Empty);
    }
    let svd = a.thin_svd().map_err(SvdError::NoConvergence)?;
    let d = svd.S().column_vector();
    let s: Vec<f64> = (0..d.nrows()).map(|i| d[i]).collect();
    Ok(Factors {
        u: svd.U().to_owned(),
        s,
        v: svd.V().to_owned(),
    })
}
