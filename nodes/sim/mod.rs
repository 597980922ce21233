//! Simulation nodes: mass-spring cloth and SPH fluid.

pub mod mass_spring;
pub mod sph;

use crate::registry::Registry;

/// Registers the simulation nodes.
pub fn register(r: &mut Registry) {
    r.with_category("sim", |r| {
        mass_spring::register(r);
        sph::register(r);
    });
}
