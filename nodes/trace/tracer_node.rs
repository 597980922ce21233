//! What the tracer nodes (`render_path`, `render_whitted`) share around the renderers:
//! progress reporting and the mapping of a renderer's error to the socket it concerns.

use crate::prelude::*;

/// A progress callback (fraction done, 0 to 1) that forwards to the context's progress
/// sink under the node's id; does nothing when the run has no sink.
pub fn progress_reporter(ctx: &ExecContext) -> impl Fn(f64) + Sync {
    let prog = ctx.progress.clone();
    let id = ctx.node_id.to_string();
    move |f: f64| {
        if let Some(p) = &prog {
            p(&id, f);
        }
    }
}

/// A renderer's error as a node error on `camera` when it is about the camera, else on
/// `scene`.
pub fn trace_error(e: String) -> NodeError {
    let socket = if e.contains("camera") {
        "camera"
    } else {
        "scene"
    };
    NodeError::invalid(socket, e)
}
