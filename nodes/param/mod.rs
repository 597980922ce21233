//! param nodes.

use crate::registry::Registry;

/// Registers the param nodes.
pub fn register(_r: &mut Registry) {}
