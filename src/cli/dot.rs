//! `cgnodes dot GRAPH`: a validated graph as Graphviz dot.

use super::validate::load_valid;
use crate::registry::Registry;
use std::path::Path;

/// `cgnodes dot GRAPH`.
pub(super) fn cmd(registry: &Registry, graph: &Path) -> i32 {
    match load_valid(registry, graph, &[]) {
        Ok(g) => {
            print!("{}", g.to_dot());
            0
        }
        Err(c) => c,
    }
}
