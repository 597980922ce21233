//! `mesh_sequence`: an animation of a simulated or animated mesh, to watch a cloth or fluid
//! run without another tool. Each frame renders the mesh with the preview view
//! (`mesh_preview`), writes the image under a `{frame}` pattern, and assembles the previews
//! of every frame so far into a GIF or APNG (as `frames_to_video` does), so it also works
//! when cgnodes runs once per frame in separate processes. The camera framing is taken from
//! the first frame's bounds and kept in `framing.json` beside the previews, so the view does
//! not follow the mesh and the animation does not jump.

use super::mesh_preview::{render_preview, Framing};
use cgnodes_api::prelude::*;
use cgnodes_formats::animation::{assemble, declare_options, read_options};
use cgnodes_formats::animation::{to_rgba8, FramePattern};

fn declare(b: &mut NodeBuilder) {
    b.doc("Renders this frame's mesh from a fixed three-quarter view and assembles the previews so far into a GIF or APNG.");
    b.sink().time_dependent();
    b.add_input::<Mesh>("mesh");
    b.add_input::<String>("path")
        .file_out()
        .doc("The animation file (.gif or .png/.apng).");
    b.add_input::<String>("previews").default("").doc(
        "Pattern of the per-frame preview PNGs under the output folder; empty: \
         <path without extension>_frames/{frame:04}.png.",
    );
    b.add_input::<i64>("width")
        .default(320)
        .range(16.0, 4096.0)
        .doc("Preview width in pixels.");
    b.add_input::<i64>("height")
        .default(240)
        .range(16.0, 4096.0)
        .doc("Preview height in pixels.");
    declare_options(b);
}

/// The default preview pattern of an animation path: `anim/cloth.gif` gives
/// `anim/cloth_frames/{frame:04}.png`.
pub fn default_previews(path: &str) -> String {
    let p = std::path::Path::new(path);
    let stem = p.file_stem().and_then(|s| s.to_str()).unwrap_or("mesh");
    let dir = p.parent().map(|d| d.to_string_lossy().to_string());
    match dir.filter(|d| !d.is_empty()) {
        Some(d) => format!("{d}/{stem}_frames/{{frame:04}}.png"),
        None => format!("{stem}_frames/{{frame:04}}.png"),
    }
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let p: String = ctx.input("path")?;
    let opts = read_options(ctx, &p)?;
    let mut previews: String = ctx.input("previews")?;
    if previews.is_empty() {
        previews = default_previews(&p);
    }
    let size = |name: &str| -> Result<u32, NodeError> {
        let v: i64 = ctx.input(name)?;
        u32::try_from(v)
            .ok()
            .filter(|v| (16..=4096).contains(v))
            .ok_or_else(|| NodeError::invalid(name, "must be within 16..4096"))
    };
    let (w, h) = (size("width")?, size("height")?);
    let pat = FramePattern::parse(&previews).map_err(|e| NodeError::invalid("previews", e))?;
    let folder = if pat.dir.as_os_str().is_empty() {
        ctx.files().out_dir.clone()
    } else {
        ctx.output_path("previews", &pat.dir.to_string_lossy())?
    };
    // The framing of the first frame, unless this is the first frame (no earlier previews).
    let sidecar = folder.join("framing.json");
    let earlier = !pat.existing(&folder, ctx.frame() - 1).is_empty();
    let kept: Option<Framing> = earlier
        .then(|| std::fs::read_to_string(&sidecar).ok())
        .flatten()
        .and_then(|t| serde_json::from_str(&t).ok());
    let framing = match kept {
        Some(f) => f,
        None => {
            let f = Framing::of(&mesh)
                .ok_or_else(|| NodeError::invalid("mesh", "no (finite) vertices to frame"))?;
            let text = serde_json::to_string(&f).unwrap_or_default();
            ctx.write_file(&sidecar, text.as_bytes())?;
            f
        }
    };
    let img = render_preview(&mesh, Some(framing), w, h)
        .map_err(|e| NodeError::invalid("mesh", e.to_string()))?;
    let rgba = to_rgba8(&img);
    let png = cgnodes_formats::png::encode_png(w, h, 4, rgba.as_raw().clone())
        .map_err(|e| NodeError::new(ErrorKind::Internal, e))?;
    let frame_path = folder.join(pat.file_name(ctx.frame()));
    ctx.write_file(&frame_path, &png)?;
    let bytes = assemble(ctx, "previews", &previews, Some(rgba), &opts)?;
    let path = ctx.output_path("path", &p)?;
    ctx.write_file(&path, &bytes)
}

/// Registers `mesh_sequence`.
pub fn register(r: &mut Registry) {
    r.add("mesh_sequence", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::default_previews;

    #[test]
    fn previews_go_beside_the_animation() {
        assert_eq!(default_previews("cloth.gif"), "cloth_frames/{frame:04}.png");
        assert_eq!(
            default_previews("semi/cloth.png"),
            "semi/cloth_frames/{frame:04}.png"
        );
    }
}
