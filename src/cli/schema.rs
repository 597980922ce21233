//! `cgnodes schema`: the JSON Schema of the graph format, typed by the registry.

use crate::registry::Registry;

/// `cgnodes schema [--untyped]`.
pub(super) fn cmd(registry: &Registry, untyped: bool) -> i32 {
    let s = if untyped {
        crate::graph::schema()
    } else {
        crate::graph::typed_schema(registry)
    };
    println!("{}", serde_json::to_string_pretty(&s).unwrap_or_default());
    0
}
