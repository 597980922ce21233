//! `print`: prints a value to standard output (and the run log).

use cgnodes_api::prelude::*;

fn declare(b: &mut NodeBuilder) {
    b.doc("Prints a value: a number, a string, or a summary of a mesh, image or table.");
    b.sink();
    b.add_input::<cgnodes_api::types::value_any::Any>("value");
    b.add_input::<String>("label")
        .default("")
        .doc("Printed before the value.");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let v = ctx
        .input_value("value")
        .cloned()
        .ok_or_else(|| NodeError::invalid("value", "no value"))?;
    let label: String = ctx.input("label")?;
    let id = ctx.node_id.to_string();
    let line = if label.is_empty() {
        format!("{id}: {}", v.summary())
    } else {
        format!("{label}: {}", v.summary())
    };
    println!("{line}");
    ctx.log(line);
    Ok(())
}

/// Registers `print`.
pub fn register(r: &mut Registry) {
    r.add("print", declare, execute);
}
