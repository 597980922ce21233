//! Mesh files in: OBJ, text USD (`.usda`), PLY (ASCII or binary) and OFF, chosen by the
//! file's extension.

use cgnodes_api::prelude::*;
use std::path::Path;

/// What `load_mesh` should pick out of a file.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// USD prim path (`/Balls/Balls`); empty: the first Mesh.
    pub prim: String,
    /// OBJ group or object name; empty: all groups merged.
    pub group: String,
    /// Apply USD `xformOp`s of the prim and its ancestors.
    pub apply_transform: bool,
}

/// Why a format's reader refused a mesh file.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshFormatError {
    /// Wavefront OBJ.
    #[error("{0}")]
    Obj(#[from] super::obj::ObjError),
    /// Text USD.
    #[error("{0}")]
    Usda(#[from] super::usda::UsdaError),
    /// Stanford PLY.
    #[error("{0}")]
    Ply(#[from] super::ply::PlyError),
    /// Geomview OFF.
    #[error("{0}")]
    Off(#[from] super::off::OffError),
}

/// Why `load_mesh` could not read a mesh file; every message starts with the file's path.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshFileError {
    /// No file at the path.
    #[error("{path}: file not found")]
    NotFound {
        /// The file.
        path: String,
    },
    /// The file exists but could not be read.
    #[error("{path}: cannot read: {error}")]
    Read {
        /// The file.
        path: String,
        /// The system's error.
        error: String,
    },
    /// An extension no reader handles.
    #[error("{path}: unknown mesh format '.{ext}' (obj, usda, ply, off are read)")]
    UnknownFormat {
        /// The file.
        path: String,
        /// Its extension, lower case.
        ext: String,
    },
    /// The format's reader refused the contents.
    #[error("{path}: {error}")]
    Format {
        /// The file.
        path: String,
        /// The reader's error (with its line where the format has lines), boxed so that the
        /// common `Ok` path does not carry the largest reader error's size.
        error: Box<MeshFormatError>,
    },
}

/// Reads a mesh file, choosing the format by extension (`obj`, `usda`/`usd`, `ply`, `off`).
/// Errors name the file and, for text formats, the offending line.
pub fn load_mesh(path: &Path, opts: &LoadOptions) -> Result<Mesh, MeshFileError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let name = path.display().to_string();
    if !path.exists() {
        return Err(MeshFileError::NotFound { path: name });
    }
    let read_err = |e: std::io::Error| MeshFileError::Read {
        path: name.clone(),
        error: e.to_string(),
    };
    let format = |error: MeshFormatError| MeshFileError::Format {
        path: name.clone(),
        error: Box::new(error),
    };
    let r: Result<Mesh, MeshFormatError> = match ext.as_str() {
        "obj" => super::obj::load_obj(path, &opts.group).map_err(Into::into),
        "usda" | "usd" => {
            let text = std::fs::read_to_string(path).map_err(read_err)?;
            super::usda::read_usda(&text, &opts.prim, opts.apply_transform).map_err(Into::into)
        }
        "ply" => {
            let bytes = std::fs::read(path).map_err(read_err)?;
            super::ply::read_ply(&bytes).map_err(Into::into)
        }
        "off" => {
            let text = std::fs::read_to_string(path).map_err(read_err)?;
            super::off::read_off(&text).map_err(Into::into)
        }
        other => {
            return Err(MeshFileError::UnknownFormat {
                path: name.clone(),
                ext: other.to_string(),
            })
        }
    };
    r.map_err(format)
}
