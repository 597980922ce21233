//! Built-in nodes, grouped by domain. Each domain's `register` adds its nodes; each node file
//! reads as declaration (`declare`), then execution (`execute`), then its tests, with the
//! algorithm itself in a plain function that Rust users can call without the runtime.

pub mod anim;
pub mod basic;
pub mod curve;
pub mod image;
pub mod learn;
pub mod linalg;
pub mod mesh;
pub mod metrics;
pub mod param;
pub mod render;
pub mod sim;
pub mod trace;

use crate::registry::Registry;

/// A registry with every built-in node (what `cgnodes` runs with before plugins are added).
pub fn builtin_registry() -> Registry {
    let mut r = Registry::new();
    register_all(&mut r);
    r
}

/// Registers every built-in node.
pub fn register_all(r: &mut Registry) {
    anim::register(r);
    basic::register(r);
    curve::register(r);
    image::register(r);
    learn::register(r);
    mesh::register(r);
    metrics::register(r);
    param::register(r);
    render::register(r);
    trace::register(r);
    sim::register(r);
}
