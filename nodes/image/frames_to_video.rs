//! `frames_to_video`: turns the images of a frame range into an animated GIF or APNG. Each
//! frame it collects the files already written under a `{frame}` pattern for the frames up
//! to the current one (by this run, or by earlier processes when cgnodes runs once per frame)
//! and writes the animation atomically, so the last frame leaves the complete animation.

use cgnodes_api::prelude::*;
use cgnodes_formats::animation::{self, assemble, declare_options, read_options};

fn declare(b: &mut NodeBuilder) {
    b.doc("Assembles the images written under a {frame} pattern, up to this frame, into an animated GIF or APNG.");
    b.sink().time_dependent();
    b.add_input::<Image>("image").optional().doc(
        "This frame's image (link what the image writer saves): the node then runs after it and \
         takes this frame from memory, encoded as image_save's PNG (sRGB).",
    );
    b.add_input::<String>("frames").doc(
        "Pattern of the frame files under the output folder, e.g. images/dam_{frame:03}.png \
         (PNG, JPEG, BMP; EXR and HDR tone-mapped).",
    );
    b.add_input::<String>("path")
        .file_out()
        .doc("The animation file (.gif or .png/.apng).");
    declare_options(b);
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let p: String = ctx.input("path")?;
    let opts = read_options(ctx, &p)?;
    let pattern: String = ctx.input("frames")?;
    let current = ctx
        .input_opt::<Arc<Image>>("image")?
        .map(|img| animation::to_rgba8(&img));
    let bytes = assemble(ctx, "frames", &pattern, current, &opts)?;
    let path = ctx.output_path("path", &p)?;
    ctx.write_file(&path, &bytes)
}

/// Registers `frames_to_video`.
pub fn register(r: &mut Registry) {
    r.add("frames_to_video", declare, execute);
}
