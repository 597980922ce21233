//! Why a plugin's output could not be decoded (`DecodeError`): one variant per way an
//! output can be wrong, each naming the key or part it is about.

use crate::plugin::npy::NpyError;
use cgnodes_api::types::{MeshError, SocketType};
use serde_json::Value as J;

/// Why a plugin's output could not be read as a value of its socket's type. `key` is the
/// JSON key naming an array, `what` the part of the value being read (`mesh 'uvs'`).
#[derive(Debug, thiserror::Error)]
pub enum DecodeError {
    /// An array key whose value is not a string.
    #[error("'{key}' should name an .npy file, got {got}")]
    NotAFileName {
        /// The JSON key.
        key: String,
        /// The value found instead.
        got: String,
    },
    /// An absolute array path outside the call folder.
    #[error("'{key}': {path} is outside the call folder; write arrays into the folder the request names")]
    OutsideFolder {
        /// The JSON key.
        key: String,
        /// The path given.
        path: String,
    },
    /// A relative array path with `..` or a root.
    #[error("'{key}': {path} leaves the call folder")]
    LeavesFolder {
        /// The JSON key.
        key: String,
        /// The path given.
        path: String,
    },
    /// An array file that could not be read.
    #[error("'{key}': {source}")]
    Array {
        /// The JSON key.
        key: String,
        /// The `.npy` reader's error.
        source: NpyError,
    },
    /// A required array key is absent.
    #[error("{what} has no '{key}'")]
    Missing {
        /// The value being read.
        what: String,
        /// The absent key.
        key: String,
    },
    /// A value that should be a JSON object is not.
    #[error("expected a {ty} object, got {got}")]
    NotAnObject {
        /// The socket type.
        ty: SocketType,
        /// The start of the JSON found.
        got: String,
    },
    /// Image pixels not of shape (H, W, 3) or (H, W, 4).
    #[error("image 'pixels' should have shape (H, W, 4) or (H, W, 3), got {0}")]
    ImageShape(String),
    /// An image side longer than `u32::MAX` ("wide" or "tall").
    #[error("image too {0}")]
    ImageSize(&'static str),
    /// A points `dim` other than 2 or 3.
    #[error("points 'dim' should be 2 or 3, got {0}")]
    PointsDim(J),
    /// A per-point scalar of the wrong shape.
    #[error("points scalar '{name}' should have shape ({n},), got {shape}")]
    ScalarShape {
        /// The scalar's name.
        name: String,
        /// The number of points.
        n: usize,
        /// The shape found.
        shape: String,
    },
    /// A per-point vector with a row count other than the number of points.
    #[error("points vector '{name}' has {rows} rows but there are {n} points")]
    VectorRows {
        /// The vector's name.
        name: String,
        /// Its rows.
        rows: usize,
        /// The number of points.
        n: usize,
    },
    /// A table without `columns`.
    #[error("a table needs 'columns': {{name: [numbers]}}")]
    NoColumns,
    /// A table column that is not a list.
    #[error("table column '{0}' should be a list of numbers")]
    ColumnNotList(String),
    /// A table entry that is not a number.
    #[error("table column '{name}': {got} is not a number")]
    ColumnNotNumber {
        /// The column.
        name: String,
        /// The entry.
        got: J,
    },
    /// A structured value (camera, light, ...) that does not deserialize.
    #[error("not a valid {ty}: {source}")]
    Serde {
        /// The socket type.
        ty: SocketType,
        /// The deserializer's error.
        source: serde_json::Error,
    },
    /// A scene output: scenes do not cross the plugin boundary.
    #[error("plugins cannot return scenes")]
    Scene,
    /// A list output that is not a JSON array.
    #[error("expected a list, got {0}")]
    NotAList(String),
    /// An item of a list output.
    #[error("item {index}: {source}")]
    Item {
        /// The item's position.
        index: usize,
        /// What is wrong with it.
        source: Box<DecodeError>,
    },
    /// A plain value's literal (the graph literal parser's message).
    #[error("{0}")]
    Literal(String),
    /// A mesh `base` that is not a string.
    #[error("mesh 'base' should name an input socket, got {0}")]
    BaseNotName(J),
    /// A mesh `base` naming no mesh input.
    #[error("mesh 'base' names '{0}', which is not a mesh input")]
    BaseNotMesh(String),
    /// Mesh triangles not of shape (F, 3).
    #[error("mesh 'triangles' should have shape (F, 3), got {0}")]
    TriangleShape(String),
    /// Mesh face counts or indices not 1-D.
    #[error("mesh 'face_counts' and 'face_indices' should be 1-D, got {counts} and {indices}")]
    FaceArrayShape {
        /// The counts' shape.
        counts: String,
        /// The indices' shape.
        indices: String,
    },
    /// Only one of face counts and face indices.
    #[error("mesh needs both 'face_counts' and 'face_indices'")]
    HalfFaces,
    /// New positions for a base mesh, without new faces, of another length.
    #[error("mesh 'positions' has {rows} rows but its base mesh has {vertices} vertices (send new faces too)")]
    PositionsVsBase {
        /// Rows sent.
        rows: usize,
        /// The base mesh's vertices.
        vertices: usize,
    },
    /// Neither positions nor a base.
    #[error("mesh has no 'positions' (and no 'base')")]
    NoPositions,
    /// Positions without faces or a base.
    #[error(
        "mesh has no faces: give 'triangles' or 'face_counts' and 'face_indices' (or a 'base')"
    )]
    NoFaces,
    /// The mesh built does not pass its checks.
    #[error("mesh: {0}")]
    Mesh(#[from] MeshError),
    /// A mesh attribute that is not `{"domain", "data"}`.
    #[error("attribute '{0}' should be {{\"domain\", \"data\"}}")]
    AttributeNotObject(String),
    /// A mesh attribute of an unsupported shape.
    #[error("attribute '{name}' should have shape (n,), (n, 2) or (n, 3), got {shape}")]
    AttributeShape {
        /// The attribute.
        name: String,
        /// The shape found.
        shape: String,
    },
    /// An integer array that could not be read as integers.
    #[error(transparent)]
    Npy(#[from] NpyError),
    /// A NaN or infinite element.
    #[error("{what}: element {index} is {value}")]
    NotFinite {
        /// The array.
        what: String,
        /// The element's position.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// An array of rows of the wrong width (`(N, 3)` for positions).
    #[error("{what} should have shape (N, {width}), got {shape}")]
    RowShape {
        /// The array.
        what: String,
        /// The row width wanted.
        width: usize,
        /// The shape found.
        shape: String,
    },
    /// Mesh index arrays that are not integers.
    #[error("mesh '{what}': {source}")]
    Indices {
        /// The array.
        what: &'static str,
        /// The conversion's error.
        source: NpyError,
    },
    /// A negative or too large mesh index.
    #[error("mesh '{what}': {index} is not a valid index")]
    BadIndex {
        /// The array.
        what: &'static str,
        /// The index.
        index: i64,
    },
    /// A domain name other than vertex, corner or face.
    #[error("{what}: unknown domain '{got}' (vertex, corner or face)")]
    UnknownDomain {
        /// The key or attribute.
        what: String,
        /// The name found.
        got: String,
    },
}
