//! Metric nodes: accuracy against a reference, for charts of accuracy against time.

pub mod compare_series;

use cgnodes_api::registry::Registry;

/// Registers this family's nodes, in the `metrics` category.
pub fn register(r: &mut Registry) {
    r.with_category("metrics", |r| {
        compare_series::register(r);
    });
}
