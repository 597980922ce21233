//! Basic nodes: constants, arithmetic, the frame number, printing and writing tables.

crate::node_domain! {
    category: "basic",
    nodes: [frame, math, print, table_write, value],
}
