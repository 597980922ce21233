//! `sph` (not implemented yet).

use crate::registry::Registry;

/// Registers `sph`.
pub fn register(_r: &mut Registry) {}
