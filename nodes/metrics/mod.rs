//! Metric nodes: accuracy against a reference, for charts of accuracy against time.

pub mod compare_series;

use crate::registry::Registry;

/// Registers the metric nodes.
pub fn register(r: &mut Registry) {
    r.with_category("metrics", |r| {
        compare_series::register(r);
    });
}
