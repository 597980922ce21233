//! Why `arap_parameterize` or `asap_parameterize` refused its input: the algorithms' own
//! error type, free of the graph runtime. The nodes map it to `NodeError` (kind and socket)
//! in `arap.rs`; the messages are those the nodes print.

/// An input the ARAP family cannot use, or a system it could not factor.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ArapError {
    /// The initial UVs are not one per vertex.
    #[error("initial UVs have {len} entries but the mesh has {vertices} vertices")]
    InitLength {
        /// Number of initial UVs.
        len: usize,
        /// Number of mesh vertices.
        vertices: usize,
    },
    /// An initial UV is NaN or infinite.
    #[error("initial UV of vertex {0} is not finite")]
    InitNotFinite(usize),
    /// The mesh has no triangle.
    #[error("mesh has no triangles")]
    NoTriangles,
    /// A triangle refers to a vertex the mesh does not have (`TriangleFrames::new`).
    #[error("triangle {0} refers to a vertex out of range")]
    VertexOutOfRange(usize),
    /// A triangle has zero or non-finite area (`TriangleFrames::new`).
    #[error(
        "triangle {triangle} (vertices {}, {}, {}) has zero area; ARAP needs non-degenerate triangles",
        .vertices[0], .vertices[1], .vertices[2]
    )]
    DegenerateTriangle {
        /// The triangle's index.
        triangle: usize,
        /// Its vertices.
        vertices: [u32; 3],
    },
    /// `ArapOptions::tolerance` is negative or not finite.
    #[error("tolerance must be finite and >= 0")]
    Tolerance,
    /// `ArapOptions::lambda` is negative or not finite.
    #[error("lambda must be finite and >= 0")]
    Lambda,
    /// `ArapOptions::pin` is not a vertex.
    #[error("pin {pin} is not a vertex (the mesh has {vertices})")]
    Pin {
        /// The requested pin.
        pin: usize,
        /// Number of mesh vertices.
        vertices: usize,
    },
    /// `arap_parameterize_prepared` was given a system built for another pin or mode.
    #[error("the prepared ARAP system was built for another pin or injective setting")]
    SystemOptions,
    /// Fold-free mode was given a start with flipped or degenerate triangles.
    #[error(
        "the initial UVs have {0} flipped or degenerate triangles; fold-free ARAP needs a fold-free start (the default Tutte initialization is one), or set injective: false"
    )]
    FoldedStart(usize),
    /// The cotangent Laplacian is not numerically positive definite.
    #[error(
        "the cotangent Laplacian could not be factored ({0}); the mesh may have nearly degenerate triangles"
    )]
    SingularLaplacian(String),
    /// ASAP needs one connected component; the mesh has this many.
    #[error("mesh has {0} connected components; ASAP needs one")]
    Components(usize),
    /// ASAP's two pins are not two different vertices of the triangles.
    #[error("pins must be two different vertices of the mesh's triangles")]
    Pins,
    /// ASAP's system is not numerically positive definite.
    #[error(
        "the ASAP system could not be factored ({0}); the mesh may have nearly degenerate triangles"
    )]
    SingularAsap(String),
}
