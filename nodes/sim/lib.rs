//! Simulation nodes: mass-spring cloth and SPH fluid.

pub mod mass_spring;
pub mod sph;

use cgnodes_api::registry::Registry;

/// Registers this family's nodes, in the `sim` category.
pub fn register(r: &mut Registry) {
    r.with_category("sim", |r| {
        mass_spring::register(r);
        sph::register(r);
    });
}
