//! render nodes.

use crate::registry::Registry;

/// Registers the render nodes.
pub fn register(_r: &mut Registry) {}
