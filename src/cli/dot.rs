//! `cgnodes dot GRAPH`: a validated graph as Graphviz dot.

use super::validate::load_args;
use super::GraphArgs;
use crate::registry::Registry;

/// `cgnodes dot GRAPH [--set ...] [--assets DIR] [--f3d-aliases FILE]`.
pub(super) fn cmd(registry: &Registry, args: &GraphArgs) -> i32 {
    match load_args(registry, args, None) {
        Ok((g, _)) => {
            print!("{}", g.to_dot());
            0
        }
        Err(c) => c,
    }
}
