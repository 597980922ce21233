//! The project's stage per frame: the geometry graph's Write USD layers, the composition
//! graph's layers (lights, merged layers), a default light when there is none, and the camera
//! (the composition's, else the default framing of the geometry over the whole frame range).

use super::ProjectError;
use crate::nodes::render::stage::scene::{camera_prim, default_camera};
use crate::nodes::render::stage::stage_nodes::{framework_light, StageLightType};
use crate::nodes::render::stage::{read_stage, Stage};
use std::path::Path;

/// Prim path of the camera `f3d-project` adds when the composition has none.
pub(super) const DEFAULT_CAMERA_PATH: &str = "/Reference/DefaultCamera";

/// The stage of one frame's geometry layers (the `.usda` files Write USD wrote).
pub(super) fn geometry_stage(files: &[std::path::PathBuf]) -> Result<Stage, ProjectError> {
    let invalid = |f: &Path, e: &dyn std::fmt::Display| {
        ProjectError::Invalid(format!("{}: {e}", f.display()))
    };
    let mut s = Stage::default();
    for f in files {
        let text = std::fs::read_to_string(f).map_err(|e| invalid(f, &e))?;
        let mut layer = read_stage(&text).map_err(|e| invalid(f, &e))?;
        // hw9 writes the particles twice (points, and Points to Mesh, whose OpenVDB surface
        // cgnodes does not build): a cloud equal to one already there is drawn once.
        layer
            .points
            .retain(|p| !s.points.iter().any(|q| q.points == p.points));
        s.merge(layer);
    }
    Ok(s)
}

/// The light added when neither the composition nor the geometry has one: a white distant
/// light of intensity 3 from over the camera's right shoulder (Rotate X 40, Rotate Z 30 on a
/// Z-up stage: it comes from above, from the front right).
pub(super) fn default_light() -> crate::nodes::render::stage::StageLight {
    framework_light(
        StageLightType::Distant,
        "DefaultLight",
        [0.0; 3],
        [40.0, 0.0, 30.0],
        [1.0; 3],
        3.0,
        [1.0, 0.0, 0.0],
        "",
    )
}

/// The frame's whole stage: `geometry` plus `composition`, a default light when there is
/// none, and the composition's camera or the default framing of `bounds`.
pub(super) fn frame_stage(
    geometry: Stage,
    composition: &Stage,
    bounds: Option<([f64; 3], [f64; 3])>,
    size: (u32, u32),
) -> Stage {
    let mut s = geometry;
    s.up_axis = composition.up_axis;
    s.merge(composition.clone());
    if s.lights.is_empty() {
        s.lights.push(default_light());
    }
    if s.camera.is_none() {
        let (lo, hi) = bounds.or(s.bounds()).unwrap_or(([-1.0; 3], [1.0; 3]));
        let cam = default_camera(lo, hi, s.up_axis, size.0, size.1);
        s.camera = Some(camera_prim(&cam, DEFAULT_CAMERA_PATH));
    }
    s
}

/// Writes the stage as `path` (atomically).
pub(super) fn write(stage: &Stage, path: &Path) -> Result<(), ProjectError> {
    let text = crate::nodes::render::stage::write_stage(stage);
    crate::io::write_atomic(path, |w| w.write_all(text.as_bytes()))
        .map_err(|e| ProjectError::Failed(format!("{}: {e}", path.display())))
}

/// The union of two optional boxes.
pub(super) fn union(
    a: Option<([f64; 3], [f64; 3])>,
    b: Option<([f64; 3], [f64; 3])>,
) -> Option<([f64; 3], [f64; 3])> {
    match (a, b) {
        (Some((l0, h0)), Some((l1, h1))) => Some((
            [l0[0].min(l1[0]), l0[1].min(l1[1]), l0[2].min(l1[2])],
            [h0[0].max(h1[0]), h0[1].max(h1[1]), h0[2].max(h1[2])],
        )),
        (x, None) | (None, x) => x,
    }
}
