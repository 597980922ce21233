//! `frame`: the current frame number, for animating parameters over `--frames`.

use cgnodes_api::prelude::*;

fn declare(b: &mut NodeBuilder) {
    b.doc("The current frame number (0 unless the graph is run with --frames).");
    b.time_dependent();
    b.add_output::<i64>("frame");
    b.add_output::<f64>("time")
        .doc("The frame number as a float.");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let f = ctx.frame();
    ctx.set_output("frame", f);
    ctx.set_output("time", f as f64);
    Ok(())
}

/// Registers `frame`.
pub fn register(r: &mut Registry) {
    r.add("frame", declare, execute);
}
