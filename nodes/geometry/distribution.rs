//! Sampling a discrete distribution by inverting its cumulative sum: environment-map
//! importance sampling and the tracers' light selection.

/// A discrete distribution sampled by inverting its cumulative sum (one binary search).
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    cdf: Vec<f32>,
    pmf: Vec<f32>,
    total: f64,
}

impl Distribution1D {
    /// The distribution proportional to the non-negative `weights`.
    pub fn new(weights: &[f64]) -> Distribution1D {
        let total: f64 = weights.iter().map(|w| w.max(0.0)).sum();
        let mut acc = 0.0;
        let mut cdf = Vec::with_capacity(weights.len());
        let mut pmf = Vec::with_capacity(weights.len());
        for w in weights {
            let w = w.max(0.0);
            acc += w;
            cdf.push(if total > 0.0 {
                (acc / total) as f32
            } else {
                0.0
            });
            pmf.push(if total > 0.0 { (w / total) as f32 } else { 0.0 });
        }
        if let Some(l) = cdf.last_mut() {
            *l = 1.0;
        }
        Distribution1D { cdf, pmf, total }
    }

    /// Sum of the weights.
    pub fn total(&self) -> f64 {
        self.total
    }

    /// Whether nothing can be sampled.
    pub fn is_empty(&self) -> bool {
        self.total <= 0.0
    }

    /// Probability of index `i`.
    #[inline(always)]
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf[i]
    }

    /// `sample(u)` and `u` remapped to a fresh uniform number within the chosen index's
    /// cdf interval (PBRT 3, section 13.6.7), for sampling a position inside the cell.
    #[inline]
    pub fn sample_remapped(&self, u: f32) -> (usize, f32) {
        let i = self.sample(u);
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let p = self.pmf[i];
        let r = if p > 0.0 { (u - lo) / p } else { 0.5 };
        (i, r.clamp(0.0, 1.0 - f32::EPSILON))
    }

    /// An index drawn with probability `pmf(i)` from uniform `u`.
    #[inline]
    pub fn sample(&self, u: f32) -> usize {
        let i = self.cdf.partition_point(|&c| c <= u);
        let mut i = i.min(self.cdf.len() - 1);
        // Skip zero-probability entries that share the cdf value.
        while self.pmf[i] == 0.0 && i + 1 < self.cdf.len() {
            i += 1;
        }
        i
    }
}
