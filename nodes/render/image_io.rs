//! Old home of the image file nodes, now in the image domain (`crate::nodes::image`); these
//! re-exports keep the old paths working.

pub use crate::nodes::image::image_load::{decode_image, ColorSpace};
pub use crate::nodes::image::image_save::{encode_image, ImageFileFormat};
pub use crate::nodes::image::srgb::{linear_to_srgb, srgb_to_linear};
