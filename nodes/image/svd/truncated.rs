//! The exact thin SVD A = U Σ V^T through faer (bidiagonalization and divide and conquer).

use super::Factors;
use faer::MatRef;

/// The thin SVD of `a` (r = min(m, n) singular triplets, values decreasing).
pub fn thin_svd(a: MatRef<'_, f64>) -> Result<Factors, String> {
    if a.nrows() == 0 || a.ncols() == 0 {
        return Err("the matrix is empty".into());
    }
    let svd = a
        .thin_svd()
        .map_err(|e| format!("the SVD did not converge: {e:?}"))?;
    let d = svd.S().column_vector();
    let s: Vec<f64> = (0..d.nrows()).map(|i| d[i]).collect();
    Ok(Factors {
        u: svd.U().to_owned(),
        s,
        v: svd.V().to_owned(),
    })
}
