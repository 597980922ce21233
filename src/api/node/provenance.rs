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
    pub fn read(path: &Path) -> Result<Provenance, String> {
        let show = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
        let bytes = std::fs::read(path).map_err(|e| show(&e))?;
        let text = match crate::io::provenance::extract(path, &bytes) {
            Some(t) => t,
            None => {
                let side = crate::io::provenance::sidecar_path(path);
                std::fs::read_to_string(&side).map_err(|_| {
                    format!(
                        "{}: no cgnodes provenance record in the file and no {}",
                        path.display(),
                        side.display()
                    )
                })?
            }
        };
        serde_json::from_str(&text).map_err(|e| show(&e))
    }

    /// Adds this record to a file already written outside a node (a sweep's CSV and chart):
    /// embedded when the format has a place for it, else as the `FILE.provenance.json`
    /// sidecar. Both writes are atomic.
    pub fn record_in(&self, path: &Path) -> Result<(), String> {
        let show = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
        let bytes = std::fs::read(path).map_err(|e| show(&e))?;
        match crate::io::provenance::embed(path, &bytes, &self.to_line()) {
            Some(b) => crate::io::write_atomic(path, |w| w.write_all(&b)).map_err(|e| show(&e)),
            None => {
                let side = crate::io::provenance::sidecar_path(path);
                let text = serde_json::to_string_pretty(self).unwrap_or_default() + "\n";
                crate::io::write_atomic(&side, |w| w.write_all(text.as_bytes()))
                    .map_err(|e| format!("{}: {e}", side.display()))
            }
        }
    }
}
