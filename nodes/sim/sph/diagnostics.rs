//! Measurements of the fluid for logs, tests and benchmarks: speed, compression, energy,
//! momentum, and the surge front and height of a dam break.

use super::state::Fluid;
use cgnodes_api::types::vec3::{axpy, dot};
use rayon::prelude::*;

impl Fluid {
    /// Largest speed.
    pub fn max_speed(&self) -> f64 {
        self.velocities
            .par_iter()
            .map(|v| dot(*v, *v))
            .reduce(|| 0.0, f64::max)
            .sqrt()
    }

    /// Largest and average compression `max(rho/rho0 - 1, 0)` (free-surface particles
    /// lack neighbours and read low densities, which is not an error).
    pub fn density_error(&self) -> (f64, f64) {
        let rho0 = self.params.rest_density;
        let e: Vec<f64> = self
            .densities
            .iter()
            .map(|r| (r / rho0 - 1.0).max(0.0))
            .collect();
        let max = e.iter().cloned().fold(0.0, f64::max);
        let avg = if e.is_empty() {
            0.0
        } else {
            e.iter().sum::<f64>() / e.len() as f64
        };
        (max, avg)
    }

    /// Kinetic energy `1/2 m sum |v|^2`.
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.mass * self.velocities.iter().map(|v| dot(*v, *v)).sum::<f64>()
    }

    /// Total momentum `m sum v`.
    pub fn momentum(&self) -> [f64; 3] {
        let mut s = [0.0; 3];
        for v in &self.velocities {
            s = axpy(s, self.mass, *v);
        }
        s
    }

    /// Front position along +x, measured from the box's left wall: the 5th-largest particle
    /// x (robust against a few splashed particles, as the SPlisHSPlasH comparison measures it,
    /// `bench/peers/sph_front.py`) plus half a spacing (the particle's extent).
    pub fn front(&self) -> f64 {
        if self.positions.is_empty() {
            return 0.0;
        }
        let mut xs: Vec<f64> = self.positions.iter().map(|p| p[0]).collect();
        let k = 4.min(xs.len() - 1);
        let idx = xs.len() - 1 - k;
        let (_, kth, _) = xs.select_nth_unstable_by(idx, |a, b| a.total_cmp(b));
        *kth + 0.5 * self.spacing[0] - self.params.box_min[0]
    }

    /// Height of the fluid above the floor (largest up coordinate plus half a spacing).
    pub fn height(&self) -> f64 {
        let up = self.up();
        self.positions
            .iter()
            .map(|p| p[up])
            .fold(f64::MIN, f64::max)
            + 0.5 * self.spacing[up]
            - self.params.box_min[up]
    }
}
