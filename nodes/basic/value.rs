//! `value_float`, `value_int`, `value_string`, `value_vec3`: constants, so one literal can
//! feed several nodes and be varied from the command line (`--set v.value=2`).

use cgnodes_api::prelude::*;

fn constant<T: Typed + Into<Value> + 'static>(r: &mut Registry, name: &str, default: T, doc: &str) {
    let doc = doc.to_string();
    r.add(
        name,
        move |b| {
            b.doc(&doc);
            b.add_input::<T>("value")
                .default(default)
                .doc("The constant.");
            b.add_output::<T>("value");
        },
        |ctx| {
            let v = ctx
                .input_value("value")
                .cloned()
                .ok_or_else(|| NodeError::invalid("value", "no value"))?;
            ctx.set_output("value", v);
            Ok(())
        },
    );
}

/// Registers the constant nodes.
pub fn register(r: &mut Registry) {
    constant(r, "value_float", 0.0f64, "A floating-point constant.");
    constant(r, "value_int", 0i64, "An integer constant.");
    constant(r, "value_string", String::new(), "A string constant.");
    constant(r, "value_vec3", [0.0f64; 3], "A 3-vector constant.");
}
