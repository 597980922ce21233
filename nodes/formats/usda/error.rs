//! Why a `.usda` layer could not be read: `UsdaError`, with the line of the layer or the prim
//! at fault. The messages are those the mesh and skeleton loaders print.

/// A text USD layer, or a prim in it, that cannot be read.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum UsdaError {
    /// A syntax error or a value of the wrong shape, at a line of the layer.
    #[error("line {line}: {message}")]
    Line {
        /// The 1-based line.
        line: usize,
        /// What is wrong there.
        message: String,
    },
    /// A prim that cannot be used, by its path; `message` names it.
    #[error("{message}")]
    Prim {
        /// The prim's path.
        path: String,
        /// What is wrong with it.
        message: String,
    },
    /// No prim at the requested path.
    #[error("no prim at '{path}'; {kinds} in the file: {found}")]
    NoPrimAt {
        /// The path asked for.
        path: String,
        /// What was looked for, plural: "meshes", "skeletons".
        kinds: &'static str,
        /// The paths of the prims of that type, comma-separated.
        found: String,
    },
    /// No path was given and the layer has no prim of the type.
    #[error("the file has no {0} prim")]
    NoneOfType(&'static str),
    /// The prim at the requested path has another type.
    #[error(
        "prim '{path}' (line {line}) is a '{found}', not a {wanted}; {kinds} in the file: {others}"
    )]
    WrongType {
        /// The prim's path.
        path: String,
        /// Its line.
        line: usize,
        /// Its type.
        found: String,
        /// The type wanted.
        wanted: &'static str,
        /// The wanted type's plural: "meshes", "skeletons".
        kinds: &'static str,
        /// The paths of the prims of the wanted type, comma-separated.
        others: String,
    },
}

impl UsdaError {
    /// An error about the prim at `path`.
    pub fn prim(path: &str, message: impl Into<String>) -> UsdaError {
        UsdaError::Prim {
            path: path.to_string(),
            message: message.into(),
        }
    }
}
