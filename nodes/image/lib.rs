//! Image nodes: reading and writing image files (linear RGBA inside, sRGB-encoded 8-bit
//! files), the sRGB transfer functions, comparing an image against a reference, warping,
//! Poisson editing, seam carving, SVD compression and Robust PCA, and animations of frame
//! sequences (`animation`, `frames_to_video`).

pub mod frames_to_video;
pub mod image_compare;
pub mod image_load;
pub mod image_save;
pub mod image_svd;
pub mod image_warp;
pub mod poisson_blend;
pub mod rpca;
pub mod seam_carve;
#[cfg(test)]
mod test_images;
pub mod warp;
pub use cgnodes_formats::{animation, file_check, srgb};

use cgnodes_api::registry::Registry;

/// An error from another crate (the sparse Cholesky factorization of cgnodes-linalg),
/// boxed with its own message so this family's typed errors can carry it whatever its type.
pub type BoxedError = Box<dyn std::error::Error + Send + Sync>;

/// Registers this family's nodes, in the `image` category.
pub fn register(r: &mut Registry) {
    r.with_category("image", |r| {
        frames_to_video::register(r);
        image_compare::register(r);
        image_load::register(r);
        image_save::register(r);
        image_svd::register(r);
        image_warp::register(r);
        poisson_blend::register(r);
        rpca::register(r);
        seam_carve::register(r);
    });
}
