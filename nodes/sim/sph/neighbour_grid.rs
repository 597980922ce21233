//! Uniform-grid neighbour search: cells the size of the support radius, particle indices
//! sorted by cell with a counting sort, queries over the 3^d surrounding cells, built and
//! queried in parallel with rayon (Ihmsen et al. 2014, "A Parallel SPH Implementation on
//! Multi-Core CPUs", the "index sort" variant).

use rayon::prelude::*;

/// Largest number of cells a grid may have (guards against a huge, sparse domain).
pub const MAX_CELLS: usize = 1 << 27;

/// Why a neighbour grid cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GridError {
    /// The points spread over more than `MAX_CELLS` cells (a huge, sparse domain, or a
    /// non-finite coordinate).
    #[error(
        "the particles spread over {cells:.3e} grid cells (more than {MAX_CELLS}); \
         use a smaller box or larger particles"
    )]
    TooManyCells {
        /// The number of cells the points' bounding box needs (NaN for non-finite points).
        cells: f64,
    },
}

/// Particle indices bucketed by uniform grid cell.
#[derive(Clone, Debug, Default)]
pub struct NeighbourGrid {
    /// Cell edge length (the support radius).
    pub cell: f64,
    origin: [f64; 3],
    dims: [usize; 3],
    /// `sorted[cell_start[c]..cell_start[c + 1]]` are the particles in cell `c`.
    cell_start: Vec<u32>,
    /// Particle indices sorted by cell.
    pub sorted: Vec<u32>,
}

impl NeighbourGrid {
    /// Buckets `points` (all finite) into cells of edge `cell`. `Err` if the points spread
    /// over more than `MAX_CELLS` cells.
    pub fn build(points: &[[f64; 3]], cell: f64) -> Result<NeighbourGrid, GridError> {
        if points.is_empty() {
            return Ok(NeighbourGrid {
                cell,
                ..Default::default()
            });
        }
        let (lo, hi) = points
            .par_iter()
            .fold(
                || ([f64::MAX; 3], [f64::MIN; 3]),
                |(mut lo, mut hi), p| {
                    for a in 0..3 {
                        lo[a] = lo[a].min(p[a]);
                        hi[a] = hi[a].max(p[a]);
                    }
                    (lo, hi)
                },
            )
            .reduce(
                || ([f64::MAX; 3], [f64::MIN; 3]),
                |(l1, h1), (l2, h2)| {
                    (
                        [l1[0].min(l2[0]), l1[1].min(l2[1]), l1[2].min(l2[2])],
                        [h1[0].max(h2[0]), h1[1].max(h2[1]), h1[2].max(h2[2])],
                    )
                },
            );
        let mut dims = [1usize; 3];
        let mut total = 1f64;
        for a in 0..3 {
            let n = ((hi[a] - lo[a]) / cell).floor() + 1.0;
            total *= n;
            dims[a] = n as usize;
        }
        if total.is_nan() || total > MAX_CELLS as f64 {
            return Err(GridError::TooManyCells { cells: total });
        }
        let mut g = NeighbourGrid {
            cell,
            origin: lo,
            dims,
            cell_start: Vec::new(),
            sorted: Vec::new(),
        };
        let keys: Vec<u32> = points.par_iter().map(|p| g.key(p) as u32).collect();
        let ncell = dims[0] * dims[1] * dims[2];
        let mut count = vec![0u32; ncell + 1];
        for &k in &keys {
            count[k as usize + 1] += 1;
        }
        for c in 0..ncell {
            count[c + 1] += count[c];
        }
        let mut fill = count.clone();
        let mut sorted = vec![0u32; points.len()];
        for (i, &k) in keys.iter().enumerate() {
            sorted[fill[k as usize] as usize] = i as u32;
            fill[k as usize] += 1;
        }
        g.cell_start = count;
        g.sorted = sorted;
        Ok(g)
    }

    fn coord(&self, p: &[f64; 3]) -> [i64; 3] {
        let mut c = [0i64; 3];
        for a in 0..3 {
            c[a] = ((p[a] - self.origin[a]) / self.cell).floor() as i64;
        }
        c
    }

    fn key(&self, p: &[f64; 3]) -> usize {
        let c = self.coord(p);
        let cl = |a: usize| c[a].clamp(0, self.dims[a] as i64 - 1) as usize;
        (cl(2) * self.dims[1] + cl(1)) * self.dims[0] + cl(0)
    }

    /// Calls `f(j)` for every indexed point `j` in the cells around `x` (a superset of the
    /// points within one cell length of `x`).
    pub fn for_each_candidate(&self, x: &[f64; 3], mut f: impl FnMut(usize)) {
        if self.sorted.is_empty() {
            return;
        }
        let c = self.coord(x);
        let range = |a: usize| {
            let lo = (c[a] - 1).max(0);
            let hi = (c[a] + 1).min(self.dims[a] as i64 - 1);
            (lo, hi)
        };
        let (z0, z1) = range(2);
        let (y0, y1) = range(1);
        let (x0, x1) = range(0);
        for z in z0..=z1 {
            for y in y0..=y1 {
                let row = (z as usize * self.dims[1] + y as usize) * self.dims[0];
                if x0 > x1 {
                    continue;
                }
                let s = self.cell_start[row + x0 as usize] as usize;
                let e = self.cell_start[row + x1 as usize + 1] as usize;
                for &j in &self.sorted[s..e] {
                    f(j as usize);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_finds_exactly_the_brute_force_neighbours() {
        let mut pts = Vec::new();
        let mut s = 12345u64;
        let mut rnd = || cgnodes_api::rng::lcg_next(&mut s);
        for _ in 0..500 {
            pts.push([rnd(), rnd() * 0.5, rnd() * 0.3]);
        }
        let h = 0.12;
        let g = NeighbourGrid::build(&pts, h).unwrap();
        for (i, p) in pts.iter().enumerate() {
            let mut a = Vec::new();
            g.for_each_candidate(p, |j| {
                let d: f64 = (0..3).map(|k| (pts[j][k] - p[k]).powi(2)).sum();
                if d < h * h {
                    a.push(j);
                }
            });
            a.sort();
            let b: Vec<usize> = (0..pts.len())
                .filter(|&j| (0..3).map(|k| (pts[j][k] - p[k]).powi(2)).sum::<f64>() < h * h)
                .collect();
            assert_eq!(a, b, "particle {i}");
        }
    }
}
