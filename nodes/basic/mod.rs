//! Basic nodes: constants, arithmetic, the frame number, printing, reading and writing tables
//! and point lists.

crate::node_domain! {
    category: "basic",
    nodes: [frame, math, points_load, print, table_load, table_slice, table_write, value],
}
