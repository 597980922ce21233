//! param nodes.

pub mod arap;

use crate::registry::Registry;

/// Registers the param nodes.
pub fn register(r: &mut Registry) {
    arap::register(r);
}
