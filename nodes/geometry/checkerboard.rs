//! A checkerboard texture: the default texture of parameterized meshes and previews.

use cgnodes_api::prelude::*;

/// A `size` x `size` checkerboard with `squares` squares per side, light and dark grey
/// (linear RGB), with the square at UV (0, 0) dark.
pub fn checkerboard(size: u32, squares: u32) -> Image {
    let squares = squares.max(1);
    let mut img = Image::new(size, size, [1.0; 4]);
    for y in 0..size {
        for x in 0..size {
            // row 0 is the top of the image, v = 1
            let i = (x as u64 * squares as u64) / size as u64;
            let j = ((size - 1 - y) as u64 * squares as u64) / size as u64;
            let c = if (i + j).is_multiple_of(2) { 0.05 } else { 0.8 };
            img.set(x, y, [c, c, c, 1.0]);
        }
    }
    img
}
