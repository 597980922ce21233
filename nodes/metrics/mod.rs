//! Metric nodes: accuracy against a reference, for charts of accuracy against time.

pub mod compare_series;
pub mod image_compare;

use crate::registry::Registry;

/// Registers the metric nodes.
pub fn register(r: &mut Registry) {
    image_compare::register(r);
    compare_series::register(r);
}
