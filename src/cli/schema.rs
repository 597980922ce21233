//! `cgnodes schema`: the JSON Schema of the graph format.

/// `cgnodes schema`.
pub(super) fn cmd() -> i32 {
    println!(
        "{}",
        serde_json::to_string_pretty(&crate::graph::schema()).unwrap_or_default()
    );
    0
}
