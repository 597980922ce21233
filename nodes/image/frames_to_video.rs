//! `frames_to_video`: turns the images of a frame range into an animated GIF or APNG. Each
//! frame it collects the files already written under a `{frame}` pattern for the frames up
//! to the current one (by this run, or by earlier processes when cgnodes runs once per frame)
//! and writes the animation atomically, so the last frame leaves the complete animation.

use super::animation::{self, AnimFormat, AnimOptions, FramePattern};
use crate::prelude::*;
use image::RgbaImage;

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

/// Declares the animation options `read_options` reads (`format`, `fps`, `loop`,
/// `max_width`), shared with `mesh_sequence`.
pub fn declare_options(b: &mut NodeBuilder) {
    b.add_choice::<AnimFormat>("format")
        .doc("gif (256 colours a frame) or apng (lossless).");
    b.add_input::<f64>("fps")
        .default(12.0)
        .range(0.1, 100.0)
        .doc("Frames per second.");
    b.add_input::<bool>("loop")
        .default(true)
        .doc("Loop forever (else play once).");
    b.add_input::<i64>("max_width")
        .default(0)
        .range(0.0, 65535.0)
        .doc("Downscale wider frames to this width (aspect kept); 0 keeps the size.");
}

/// Reads the animation options of a node with `format`, `fps`, `loop` and `max_width`
/// sockets (`frames_to_video`, `mesh_sequence`), checking the path's extension.
pub fn read_options(ctx: &ExecContext, path: &str) -> Result<AnimOptions, NodeError> {
    let format: AnimFormat = ctx.choice("format")?;
    let fps: f64 = ctx.input("fps")?;
    if !(fps.is_finite() && (0.1..=100.0).contains(&fps)) {
        return Err(NodeError::invalid("fps", "must be within 0.1..100"));
    }
    let max_width: i64 = ctx.input("max_width")?;
    let max_width = u32::try_from(max_width)
        .ok()
        .filter(|w| *w <= 65535)
        .ok_or_else(|| NodeError::invalid("max_width", "must be within 0..65535"))?;
    let ext = std::path::Path::new(path)
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let ok = match format {
        AnimFormat::Gif => ext == "gif",
        AnimFormat::Apng => ext == "png" || ext == "apng",
    };
    if !ok {
        let want = match format {
            AnimFormat::Gif => ".gif",
            AnimFormat::Apng => ".png or .apng",
        };
        return Err(NodeError::invalid(
            "path",
            format!("'{path}': format {format:?} writes {want} files"),
        ));
    }
    Ok(AnimOptions {
        format,
        fps,
        looped: ctx.input("loop")?,
        max_width,
    })
}

/// The frames of `pattern` (relative to the output folder) up to the current frame, read as
/// 8-bit sRGB and prepared for `opts` (memoized per file), with `current` (this frame's
/// image, if given) in place of this frame's file, assembled into the animation's bytes.
/// `socket` names the pattern's socket for errors.
pub fn assemble(
    ctx: &ExecContext,
    socket: &str,
    pattern: &str,
    current: Option<RgbaImage>,
    opts: &AnimOptions,
) -> Result<Vec<u8>, NodeError> {
    let bad = |e: String| NodeError::invalid(socket, e);
    let pat = FramePattern::parse(pattern).map_err(bad)?;
    let folder = if pat.dir.as_os_str().is_empty() {
        ctx.files().out_dir.clone()
    } else {
        ctx.output_path(socket, &pat.dir.to_string_lossy())?
    };
    let frame = ctx.frame();
    let mut frames = Vec::new();
    for (f, p) in pat.existing(&folder, frame) {
        if f == frame && current.is_some() {
            continue;
        }
        frames.push(animation::prepare_file(&p, opts).map_err(bad)?);
    }
    if let Some(c) = current {
        frames.push(Arc::new(animation::prepare(&c, opts).map_err(bad)?));
    }
    if frames.is_empty() {
        return Err(bad(format!(
            "no file matches '{pattern}' under {} for frames up to {frame}",
            folder.display()
        )));
    }
    animation::encode_prepared(&frames, opts).map_err(|e| {
        bad(format!(
            "'{pattern}': {e} (files of an earlier run at another size? remove them)"
        ))
    })
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
