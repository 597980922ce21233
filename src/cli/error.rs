//! Errors of the command line's own file handling: a file it reads or writes, and what went
//! wrong with it (`PATH: reason`, the form every command prints).

use std::path::{Path, PathBuf};

/// A file the command line could not read, parse or write.
#[derive(Debug, thiserror::Error)]
#[error("{}: {source}", .path.display())]
pub struct FileError {
    /// The file.
    pub path: PathBuf,
    /// What went wrong: the system's or the parser's error.
    pub source: Box<dyn std::error::Error + Send + Sync>,
}

impl FileError {
    /// `source` about `path`.
    pub fn new(path: &Path, source: impl Into<Box<dyn std::error::Error + Send + Sync>>) -> Self {
        FileError {
            path: path.to_path_buf(),
            source: source.into(),
        }
    }

    /// A closure for `map_err` that puts `path` on an error.
    pub fn at<E: Into<Box<dyn std::error::Error + Send + Sync>>>(
        path: &Path,
    ) -> impl FnOnce(E) -> FileError + '_ {
        move |e| FileError::new(path, e)
    }
}
