//! `cgnodes provenance FILE [--json]`: what made a file a run wrote (`node::Provenance`).

use super::EXIT_USAGE;
use crate::node::Provenance;
use std::path::Path;

/// Prints the provenance record of `file`, as text or JSON; exit code 2 when it has none.
pub(super) fn cmd(file: &Path, json: bool) -> i32 {
    let p = match Provenance::read(file) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_USAGE;
        }
    };
    if json {
        println!("{}", serde_json::to_string_pretty(&p).unwrap_or_default());
        return 0;
    }
    println!("file:       {}", file.display());
    println!("written by: cgnodes {}", p.cgnodes);
    println!("graph:      {} ({})", p.graph, p.graph_hash);
    println!("node:       {} ({})", p.node, p.node_type);
    println!("frame:      {}", p.frame);
    for (k, v) in &p.params {
        println!("  {k} = {v}");
    }
    0
}
