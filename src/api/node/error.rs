//! Node errors: what kind of failure a node reports (recorded per run by `cgnodes sweep`),
//! the socket at fault and a message for a person.

use serde::{Deserialize, Serialize};
use std::path::Path;

/// What kind of failure a node reports; `cgnodes sweep` records it per run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorKind {
    /// An input value the node cannot use (out of range, wrong shape, NaN).
    InvalidInput,
    /// The mesh has the wrong topology (not a disk, not manifold, closed).
    Topology,
    /// A simulation blew up (NaN, infinity, energy growth).
    Unstable,
    /// A parameterization or deformation folded triangles.
    Folded,
    /// A linear system was singular or not positive definite.
    Singular,
    /// Reading or writing a file failed.
    Io,
    /// The node is not supported in this configuration.
    Unsupported,
    /// An external plugin failed or timed out.
    Plugin,
    /// A bug in cgnodes: please report it.
    Internal,
}

impl std::fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = serde_json::to_value(self).unwrap_or_default();
        write!(f, "{}", s.as_str().unwrap_or("error"))
    }
}

/// A node's failure: its kind, the socket at fault (if any) and a message.
#[derive(Clone, Debug, thiserror::Error)]
#[error("{}{message}", socket.as_ref().map(|s| format!("socket '{s}': ")).unwrap_or_default())]
pub struct NodeError {
    /// What kind of failure.
    pub kind: ErrorKind,
    /// The socket at fault.
    pub socket: Option<String>,
    /// What went wrong, for a person.
    pub message: String,
}

impl NodeError {
    /// A failure of `kind`.
    pub fn new(kind: ErrorKind, message: impl Into<String>) -> NodeError {
        NodeError {
            kind,
            socket: None,
            message: message.into(),
        }
    }
    /// A bad value on input `socket`.
    pub fn invalid(socket: &str, message: impl Into<String>) -> NodeError {
        NodeError {
            kind: ErrorKind::InvalidInput,
            socket: Some(socket.to_string()),
            message: message.into(),
        }
    }
    /// A mesh with the wrong topology on input `socket`.
    pub fn topology(socket: &str, message: impl Into<String>) -> NodeError {
        NodeError {
            kind: ErrorKind::Topology,
            socket: Some(socket.to_string()),
            message: message.into(),
        }
    }
    /// A simulation that blew up.
    pub fn unstable(message: impl Into<String>) -> NodeError {
        NodeError::new(ErrorKind::Unstable, message)
    }
    /// A singular or indefinite system.
    pub fn singular(message: impl Into<String>) -> NodeError {
        NodeError::new(ErrorKind::Singular, message)
    }
    /// A file that could not be read or written.
    pub fn io(path: &Path, err: impl std::fmt::Display) -> NodeError {
        NodeError::new(ErrorKind::Io, format!("{}: {err}", path.display()))
    }
    /// Sets the socket at fault.
    pub fn at(mut self, socket: &str) -> NodeError {
        self.socket = Some(socket.to_string());
        self
    }
}
