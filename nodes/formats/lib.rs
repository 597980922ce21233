//! cgnodes-formats: the file formats node families and the run report share. Meshes in
//! (`mesh_file` over `obj`, `ply`, `off`, `usda`), images in and out (`image_file`, checked
//! whole by `file_check` before decoding), animations (`animation`), PNG encoding and the
//! chart font. Plain functions over the API's types, callable without the runtime.

pub mod animation;
pub mod file_check;
pub mod font;
pub mod image_file;
pub mod mesh_file;
pub mod obj;
pub mod obj_companions;
pub mod off;
pub mod ply;
pub mod png;
pub mod srgb;
pub mod usda;
