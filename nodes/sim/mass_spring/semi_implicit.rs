//! Semi-implicit (symplectic) Euler, as in the course's assignment 8:
//! `v <- damping (v + h M^-1 f(x))`, then `x <- x + h v` with the new velocity.
//!
//! Symplectic Euler is conditionally stable: on a linear spring system it is bounded iff
//! `h < 2 / omega_max` (omega_max^2 = largest eigenvalue of M^-1 K), and its discrete
//! period is `2 pi h / acos(1 - (omega h)^2 / 2)` (Hairer, Lubich & Wanner, *Geometric
//! Numerical Integration*, 2006, ch. I.1).

use super::springs::{add_collider_forces, axpy, spring_forces, Incidence, Model, Sphere, State};
use rayon::prelude::*;

/// Scratch buffers and the vertex-spring incidence, kept between steps.
#[derive(Clone, Debug, Default)]
pub struct SemiImplicit {
    inc: Incidence,
    f: Vec<[f64; 3]>,
}

impl SemiImplicit {
    /// Prepares the integrator for `m`.
    pub fn new(m: &Model) -> SemiImplicit {
        SemiImplicit {
            inc: Incidence::new(&m.springs, m.num_vertices()),
            f: vec![[0.0; 3]; m.num_vertices()],
        }
    }

    /// Advances `st` by one step of length `h`; fixed vertices keep position and zero velocity.
    pub fn step(&mut self, m: &Model, st: &mut State, h: f64, sphere: Option<&Sphere>) {
        self.f.resize(m.num_vertices(), [0.0; 3]);
        spring_forces(&self.inc, &st.x, &mut self.f);
        add_collider_forces(sphere, &st.x, &m.fixed, &mut self.f);
        let f = &self.f;
        st.x.par_iter_mut()
            .zip(st.v.par_iter_mut())
            .enumerate()
            .with_min_len(4096)
            .for_each(|(i, (x, v))| {
                if m.fixed[i] {
                    *v = [0.0; 3];
                    return;
                }
                let a = axpy(m.gravity, 1.0 / m.mass[i], f[i]);
                let nv = axpy(*v, h, a);
                *v = [nv[0] * m.damping, nv[1] * m.damping, nv[2] * m.damping];
                *x = axpy(*x, h, *v);
            });
    }
}
