//! cgnodes-geometry: geometry that several node families use. Mesh primitives (`grid`,
//! `plane`), affine transforms (`transform`), vertex selections (`vertex_select`), colour
//! maps (`colormap`), the octahedron table (`octahedron`), textures (`texture`, `checkerboard`), the creased and normal-mapped
//! scene geometry the rasterizer and the tracers share (`scene_geometry`), and environment
//! lights (`environment`) with the f32 vectors (`v3`) and discrete distributions
//! (`distribution`) they are sampled with.

pub mod checkerboard;
pub mod colormap;
pub mod distribution;
pub mod environment;
pub mod grid;
pub mod octahedron;
pub mod plane;
pub mod scene_geometry;
pub mod texture;
pub mod transform;
pub mod v3;
pub mod vertex_select;
