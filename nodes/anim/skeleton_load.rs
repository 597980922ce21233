//! `skeleton_load`: reads a UsdSkel `Skeleton` prim (joints, bind and rest transforms) and
//! its bound `SkelAnimation` from a `.usda` file.

use cgnodes_api::prelude::*;
use cgnodes_formats::usda::{parse_usda, read_skeleton, UsdaError};
use std::path::{Path, PathBuf};

/// Why a skeleton could not be loaded, with the file's path.
#[derive(Debug, thiserror::Error)]
pub enum SkeletonFileError {
    /// The file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file is not valid USDA, or holds no such Skeleton.
    #[error("{}: {source}", path.display())]
    Usda {
        /// The file.
        path: PathBuf,
        /// The reader's error (boxed: it is large).
        source: Box<UsdaError>,
    },
}

/// Reads the Skeleton at `prim` (the first one when empty) from the `.usda` file at `path`.
pub fn load_skeleton(path: &Path, prim: &str) -> Result<Skeleton, SkeletonFileError> {
    let usda = |source: UsdaError| SkeletonFileError::Usda {
        path: path.to_path_buf(),
        source: Box::new(source),
    };
    let text = std::fs::read_to_string(path).map_err(|source| SkeletonFileError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let layer = parse_usda(&text).map_err(usda)?;
    read_skeleton(&layer, prim).map_err(usda)
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Reads a UsdSkel Skeleton and its animation from a .usda file.");
    b.add_input::<String>("path")
        .file_in()
        .doc("A .usda file, relative to the graph's folder (or an --assets folder).");
    b.add_input::<String>("prim")
        .default("")
        .doc("Prim path of the Skeleton, such as /Model/Skel; empty: the first Skeleton.");
    b.add_output::<Skeleton>("skeleton");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let p: String = ctx.input("path")?;
    let prim: String = ctx.input("prim")?;
    let path = ctx.input_path(&p);
    if !path.exists() {
        return Err(
            NodeError::new(ErrorKind::Io, format!("{}: file not found", path.display())).at("path"),
        );
    }
    let socket = if prim.is_empty() { "path" } else { "prim" };
    let skel =
        load_skeleton(&path, &prim).map_err(|e| NodeError::invalid(socket, e.to_string()))?;
    ctx.log(format!(
        "{} joints, {}",
        skel.joints.len(),
        match &skel.animation {
            Some(a) => format!("animated by '{}' ({} joints)", a.prim, a.joints.len()),
            None => "no animation".into(),
        }
    ));
    ctx.set_output("skeleton", skel);
    Ok(())
}

/// Registers `skeleton_load`.
pub fn register(r: &mut Registry) {
    r.add("skeleton_load", declare, execute);
}
