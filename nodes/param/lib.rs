//! Parameterization nodes: boundary mapping, minimal surfaces, Tutte's embedding with three
//! weightings, texture mapping, UV layout rendering and distortion metrics.

pub mod arap;
pub mod boundary_map;
pub mod laplacian;
pub mod laplacian_rows;
pub mod minimal_surface;
pub mod render_uv;
pub mod texture_map;
pub mod triangles;
pub mod tutte;
pub mod uv_metrics;

use cgnodes_api::registry::Registry;

/// Registers this family's nodes, in the `param` category.
pub fn register(r: &mut Registry) {
    r.with_category("param", |r| {
        arap::register(r);
        boundary_map::register(r);
        minimal_surface::register(r);
        render_uv::register(r);
        texture_map::register(r);
        tutte::register(r);
        uv_metrics::register(r);
    });
}
