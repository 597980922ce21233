//! Text USD (`.usda`) meshes: a parser for the subset Framework3D and Blender write, and a
//! writer Framework3D can open.
//!
//! No USD library exists for Rust, so this reads the layer syntax (prims with `def`/`over`/
//! `class`, typed attributes, relationships, metadata in parentheses, arrays, tuples, paths,
//! `timeSamples` dictionaries) into a small tree, then takes a `Mesh` prim's `points`,
//! `faceVertexCounts`, `faceVertexIndices`, `normals`, `primvars:UVMap` (or `primvars:st`),
//! `primvars:displayColor`, other simple primvars, and the `xformOp`s of the prim and its
//! ancestors (USD row-vector convention: `p_world = p * M_local * M_parent ...`). Anything
//! it does not understand is an error with the line number, never a guess.
//!
//! Errors are `UsdaError` (`error`), with the line or prim at fault.
//!
//! Layout: `lexer` (tokens) -> `layer` (the prim tree) -> `access` (typed values, prim
//! lookup) and `transform` (xformOps), used by `read` (Mesh prims) and `skel` (UsdSkel: skeletons,
//! animations, a mesh's skinning binding);
//! `write` emits a layer, `write_anim` one with the points of many frames as `timeSamples`.

pub mod access;
pub mod error;
pub mod layer;
mod lexer;
pub mod read;
pub mod skel;
pub mod transform;
pub mod write;
pub mod write_anim;

pub use access::mesh_paths;
pub use error::UsdaError;
pub use layer::{parse_usda, UsdAttr, UsdLayer, UsdPrim, UsdValue};
pub use read::{read_usda, reverse_faces};
pub use skel::read_skeleton;
pub use write::{usd_identifier, write_usda};

#[cfg(test)]
mod tests;
