//! Metric nodes: accuracy against a reference, for charts of accuracy against time.

crate::node_domain! {
    category: "metrics",
    nodes: [compare_series],
}
