//! Simulation nodes: mass-spring cloth and SPH fluid.

crate::node_domain! {
    category: "sim",
    nodes: [mass_spring, sph],
}
