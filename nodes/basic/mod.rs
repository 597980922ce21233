//! Basic nodes: constants, arithmetic, the frame number, printing and writing tables.

pub mod frame;
pub mod math;
pub mod print;
pub mod table_write;
pub mod value;

use crate::registry::Registry;

/// Registers the basic nodes.
pub fn register(r: &mut Registry) {
    r.with_category("basic", |r| {
        value::register(r);
        math::register(r);
        frame::register(r);
        print::register(r);
        table_write::register(r);
    });
}
