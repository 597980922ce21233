//! `mass_spring` (not implemented yet).

use crate::registry::Registry;

/// Registers `mass_spring`.
pub fn register(_r: &mut Registry) {}
