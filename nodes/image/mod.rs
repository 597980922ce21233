//! Image nodes: reading and writing image files (linear RGBA inside, sRGB-encoded 8-bit
//! files), the sRGB transfer functions, and comparing an image against a reference.

pub mod image_compare;
pub mod image_load;
pub mod image_save;
pub mod srgb;

use crate::registry::Registry;

/// Registers the image nodes.
pub fn register(r: &mut Registry) {
    r.with_category("image", |r| {
        image_load::register(r);
        image_save::register(r);
        image_compare::register(r);
    });
}
