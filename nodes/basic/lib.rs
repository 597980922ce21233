//! Basic nodes: constants, arithmetic, the frame number, printing, reading and writing tables
//! and point lists.

pub mod frame;
pub mod math;
pub mod points_load;
pub mod print;
pub mod table_load;
pub mod table_slice;
pub mod table_write;
pub mod value;

use cgnodes_api::registry::Registry;

/// Registers this family's nodes, in the `basic` category.
pub fn register(r: &mut Registry) {
    r.with_category("basic", |r| {
        frame::register(r);
        math::register(r);
        points_load::register(r);
        print::register(r);
        table_load::register(r);
        table_slice::register(r);
        table_write::register(r);
        value::register(r);
    });
}
