//! `Provenance`: what made a written file (cgnodes version, the graph's hash, the node, its
//! parameters and the frame), filled by the executor into each node's `ExecContext` and
//! recorded in every file the node writes (`crate::io::provenance` says where per format),
//! so a result can be traced back and re-run (`cgnodes provenance FILE`).

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// What made a written file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// The cgnodes version that wrote the file.
    pub cgnodes: String,
    /// The graph file (as given on the command line; `<dict>` for a Python dict graph).
    pub graph: String,
    /// `blake3:` and the BLAKE3 hash of the graph file's bytes (of the canonical JSON for a
    /// Python dict graph), before `--set` overrides; those show in `params`.
    pub graph_hash: String,
    /// The id of the node that wrote the file.
    pub node: String,
    /// Its type.
    pub node_type: String,
    /// Its literal parameters as run (after `--set`), by input socket; linked inputs and
    /// defaults are not listed.
    pub params: BTreeMap<String, serde_json::Value>,
    /// The frame.
    pub frame: i64,
}

/// Why a provenance record could not be read from or added to a written file.
#[derive(Debug, thiserror::Error)]
pub enum ProvenanceError {
    /// The file (or its sidecar) could not be read or written.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// The record is not JSON of a provenance record.
    #[error("{}: {source}", .path.display())]
    Json {
        /// The file.
        path: std::path::PathBuf,
        /// The parser's error.
        source: serde_json::Error,
    },
    /// Neither an embedded record nor a sidecar.
    #[error("{}: no cgnodes provenance record in the file and no {}", .path.display(), .sidecar.display())]
    NoRecord {
        /// The file.
        path: std::path::PathBuf,
        /// The sidecar looked for.
        sidecar: std::path::PathBuf,
    },
}

impl Provenance {
    /// `blake3:HEX` of a graph file's bytes.
    pub fn hash_graph(bytes: &[u8]) -> String {
        format!("blake3:{}", blake3::hash(bytes).to_hex())
    }

    /// The record as one line of ASCII JSON.
    pub fn to_line(&self) -> String {
        crate::io::provenance::ascii_json(&serde_json::to_value(self).unwrap_or_default())
    }

    /// Reads the provenance of a written file: embedded in it, or from its sidecar
    /// `FILE.provenance.json`.
    pub fn read(path: &Path) -> Result<Provenance, ProvenanceError> {
        let io = |source| ProvenanceError::Io {
            path: path.into(),
            source,
        };
        let bytes = std::fs::read(path).map_err(io)?;
        let text = match crate::io::provenance::extract(path, &bytes) {
            Some(t) => t,
            None => {
                let side = crate::io::provenance::sidecar_path(path);
                std::fs::read_to_string(&side).map_err(|_| ProvenanceError::NoRecord {
                    path: path.into(),
                    sidecar: side.clone(),
                })?
            }
        };
        serde_json::from_str(&text).map_err(|source| ProvenanceError::Json {
            path: path.into(),
            source,
        })
    }

    /// Adds this record to a file already written outside a node (a sweep's CSV and chart):
    /// embedded when the format has a place for it, else as the `FILE.provenance.json`
    /// sidecar. Both writes are atomic.
    pub fn record_in(&self, path: &Path) -> Result<(), ProvenanceError> {
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| ProvenanceError::Io { path, source }
        };
        let bytes = std::fs::read(path).map_err(io(path))?;
        match crate::io::provenance::embed(path, &bytes, &self.to_line()) {
            Some(b) => crate::io::write_atomic(path, |w| w.write_all(&b)).map_err(io(path)),
            None => {
                let side = crate::io::provenance::sidecar_path(path);
                let text = serde_json::to_string_pretty(self).unwrap_or_default() + "\n";
                crate::io::write_atomic(&side, |w| w.write_all(text.as_bytes())).map_err(io(&side))
            }
        }
    }
}
