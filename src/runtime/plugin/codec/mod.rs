//! How socket values travel between cgnodes and a plugin process: plain values as JSON
//! literals, heavy values (meshes, images, points, curves) as JSON objects that name `.npy`
//! files in the call's temporary folder, small structured values (tables, cameras, lights,
//! materials, skeletons) as JSON objects. The layouts are documented in `docs/plugins.md`.

mod decode;
mod decode_error;
mod encode;
#[cfg(test)]
mod tests;

pub use decode::{decode, DecodeError};
pub use encode::{encode, EncodeError};

use cgnodes_api::types::SocketType;

/// Whether values of socket type `ty` can cross the plugin boundary.
pub fn supported(ty: &SocketType) -> bool {
    match ty {
        SocketType::Scene => false,
        SocketType::List(inner) => supported(inner),
        _ => true,
    }
}
