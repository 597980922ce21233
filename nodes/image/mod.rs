//! Image nodes: reading and writing image files (linear RGBA inside, sRGB-encoded 8-bit
//! files), the sRGB transfer functions, comparing an image against a reference, warping,
//! Poisson editing, seam carving, SVD compression and Robust PCA, and animations of frame
//! sequences (`animation`, `frames_to_video`).

crate::node_domain! {
    category: "image",
    nodes: [frames_to_video, image_compare, image_load, image_save, image_svd, image_warp, poisson_blend, rpca, seam_carve],
    modules: [animation, file_check, srgb, warp],
}
