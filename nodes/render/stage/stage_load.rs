//! `stage_load`: reads a USDA stage (what `cgnodes f3d-project` writes per frame, or any
//! layer with meshes, points, UsdLux lights and a camera) into a `Scene` and its `Camera`.
//! Framework3D's `render_scene_camera`, `_meshes`, `_materials` and `_lights` map onto it.
//! A dome light's texture resolves next to the stage, then in the graph's and `--assets`
//! folders; when it is missing the dome keeps its constant colour, with a warning.

use super::read::read_stage;
use super::scene::{stage_to_scene, TextureError};
use cgnodes_api::prelude::*;
use cgnodes_formats::image_file::{decode_image, ColorSpace};

fn declare(b: &mut NodeBuilder) {
    b.doc("Reads a USDA stage (meshes, points, UsdLux lights, camera) into a scene and camera.");
    b.add_input::<String>("path")
        .file_in()
        .doc("USDA file, relative to the graph's folder.");
    b.add_input::<i64>("width")
        .default(640i64)
        .range(1.0, 16384.0)
        .doc("Image width of the camera, pixels.");
    b.add_input::<i64>("height")
        .default(480i64)
        .range(1.0, 16384.0)
        .doc("Image height of the camera, pixels.");
    b.add_output::<Scene>("scene")
        .doc("Meshes (points as small octahedra), materials, lights; the camera too.");
    b.add_output::<Camera>("camera")
        .doc("The stage's camera, else the default framing of its geometry.");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let p: String = ctx.input("path")?;
    let (w, h): (i64, i64) = (ctx.input("width")?, ctx.input("height")?);
    for (s, v) in [("width", w), ("height", h)] {
        if !(1..=16384).contains(&v) {
            return Err(NodeError::invalid(s, format!("{v} is not in 1..=16384")));
        }
    }
    let path = ctx.input_path(&p);
    let text = std::fs::read_to_string(&path).map_err(|e| NodeError::io(&path, e).at("path"))?;
    let stage = read_stage(&text)
        .map_err(|e| NodeError::invalid("path", format!("{}: {e}", path.display())))?;
    // Each point becomes an octahedron: 6 positions and UVs, 8 triangles (about 300 bytes).
    let points: u64 = stage.points.iter().map(|p| p.points.len() as u64).sum();
    let what = format!("{}: {points} points as octahedra", path.display());
    ctx.reserve_bytes("path", &what, cgnodes_api::node::bytes_of(&[points, 300]))?;
    let dir = path.parent().map(|d| d.to_path_buf()).unwrap_or_default();
    let files = ctx.files().clone();
    let mut load = |file: &str| -> Result<Option<Arc<Image>>, TextureError> {
        let near = dir.join(file);
        let found = if near.exists() {
            near
        } else {
            files.input_path(file)
        };
        if !found.exists() {
            return Ok(None);
        }
        let bytes = std::fs::read(&found).map_err(|source| TextureError::Read {
            path: found.clone(),
            source,
        })?;
        let img = decode_image(&bytes, ColorSpace::Raw).map_err(|e| TextureError::Decode {
            path: found.clone(),
            source: e.into(),
        })?;
        Ok(Some(Arc::new(img)))
    };
    let mut warnings = Vec::new();
    let (scene, camera) = stage_to_scene(&stage, w as u32, h as u32, &mut load, &mut warnings)
        .map_err(|e| NodeError::invalid("path", format!("{}: {e}", path.display())))?;
    for wn in warnings {
        ctx.log(format!("warning: {wn}"));
    }
    ctx.log(format!(
        "{} meshes, {} point clouds ({} points), {} lights, {} camera",
        stage.meshes.len(),
        stage.points.len(),
        stage.points.iter().map(|p| p.points.len()).sum::<usize>(),
        stage.lights.len(),
        if stage.camera.is_some() {
            "stage"
        } else {
            "default"
        }
    ));
    ctx.set_output("scene", scene);
    ctx.set_output("camera", camera);
    Ok(())
}

/// Registers `stage_load`.
pub fn register(r: &mut Registry) {
    r.add("stage_load", declare, execute);
}
