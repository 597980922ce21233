//! The composition nodes: each writes a USDA layer (text) that `cgnodes f3d-project` puts on
//! the project's stage, as Framework3D's composition nodes write into its global stage.
//! `stage_light` is `comp_add_point_light`, `_distant_light`, `_dome_light` and
//! `_rect_light` (the light at `/Reference/XForm<Path>/<Path>` with the framework's
//! transforms: a point light translated, the others turned by Rotate X, then Y, then Z, a
//! rect light turned and then translated); `stage_read` is `comp_read_usd` (a file's meshes,
//! points, lights and camera, transforms applied); `stage_merge` is `comp_merge_to_global`
//! (a layer's prims moved under `/Reference/<Path>`).

use super::model::{LightKind, Stage, StageLight};
use super::read::read_stage;
use super::write::write_stage;
use cgnodes_api::prelude::*;
use cgnodes_formats::usda::transform::{rotation, Mat4};
use cgnodes_formats::usda::usd_identifier;

/// Which UsdLux light `stage_light` adds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StageLightType {
    /// A sphere light (Framework3D's point light).
    Point,
    /// A distant light.
    Distant,
    /// A dome light.
    Dome,
    /// A rect light.
    Rect,
}

impl Choice for StageLightType {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("point", StageLightType::Point),
        ("distant", StageLightType::Distant),
        ("dome", StageLightType::Dome),
        ("rect", StageLightType::Rect),
    ];
}

/// The light Framework3D's `comp_add_*_light` node defines, as a one-light stage: `path` is
/// its `Path` widget, `position` X/Y/Z, `rotate` Rotate X/Y/Z in degrees.
#[allow(clippy::too_many_arguments)]
pub fn framework_light(
    ty: StageLightType,
    path: &str,
    position: [f64; 3],
    rotate: [f64; 3],
    color: [f64; 3],
    intensity: f64,
    size: [f64; 3],
    file: &str,
) -> StageLight {
    let id = usd_identifier(path.trim_matches('/'));
    let mut t = Mat4::identity();
    for k in 0..3 {
        t[(3, k)] = position[k];
    }
    // GfMatrix4d products as Framework3D writes them: r_x * r_y * r_z (* t).
    let r = rotation(0, rotate[0]) * rotation(1, rotate[1]) * rotation(2, rotate[2]);
    let (kind, transform) = match ty {
        StageLightType::Point => (LightKind::Sphere { radius: size[0] }, t),
        StageLightType::Distant => (LightKind::Distant { angle: size[0] }, r),
        StageLightType::Dome => (
            LightKind::Dome {
                file: file.to_string(),
            },
            r,
        ),
        StageLightType::Rect => (
            LightKind::Rect {
                width: size[1],
                height: size[2],
            },
            r * t,
        ),
    };
    StageLight {
        path: format!("/Reference/XForm{id}/{id}"),
        kind,
        color,
        intensity,
        transform,
    }
}

fn declare_light(b: &mut NodeBuilder) {
    b.doc(
        "Adds a UsdLux light to a project's stage (Framework3D's comp_add_*_light): a USDA layer.",
    );
    b.add_choice::<StageLightType>("kind")
        .doc("point (a sphere light), distant, dome or rect.");
    b.add_input::<[f64; 3]>("position")
        .default([0.0, 0.0, 0.0])
        .doc("X, Y, Z (point and rect lights).");
    b.add_input::<[f64; 3]>("rotate")
        .default([0.0, 0.0, 0.0])
        .doc("Rotate X, Y, Z in degrees (distant, dome and rect lights).");
    b.add_input::<Color>("color")
        .default(Color([1.0, 1.0, 1.0]))
        .doc("R, G, B (linear).");
    b.add_input::<f64>("intensity")
        .default(1.0)
        .min(0.0)
        .doc("inputs:intensity (Framework3D leaves USD's default 1).");
    b.add_input::<f64>("radius")
        .default(0.1)
        .min(0.0)
        .doc("Sphere radius of a point light.");
    b.add_input::<f64>("angle")
        .default(1.0)
        .min(0.0)
        .doc("Angular diameter of a distant light, degrees.");
    b.add_input::<f64>("width")
        .default(0.5)
        .min(0.0)
        .doc("Width of a rect light.");
    b.add_input::<f64>("height")
        .default(0.5)
        .min(0.0)
        .doc("Height of a rect light.");
    b.add_input::<String>("file")
        .default("")
        .doc("A dome light's texture (equirectangular EXR/HDR/PNG), as written on the stage.");
    b.add_input::<String>("path")
        .default("Light")
        .doc("Prim name: the light lands at /Reference/XForm<path>/<path>.");
    b.add_output::<String>("layer")
        .doc("The light as a USDA layer.");
}

fn execute_light(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let ty = ctx.choice::<StageLightType>("kind")?;
    let c: Color = ctx.input("color")?;
    let position: [f64; 3] = ctx.input("position")?;
    let rotate: [f64; 3] = ctx.input("rotate")?;
    let intensity: f64 = ctx.input("intensity")?;
    let size = [
        ctx.input::<f64>(match ty {
            StageLightType::Distant => "angle",
            _ => "radius",
        })?,
        ctx.input::<f64>("width")?,
        ctx.input::<f64>("height")?,
    ];
    for (s, v) in [("position", position), ("rotate", rotate), ("color", c.0)] {
        if v.iter().any(|x| !x.is_finite()) {
            return Err(NodeError::invalid(s, "values must be finite"));
        }
    }
    if c.0.iter().any(|x| *x < 0.0) {
        return Err(NodeError::invalid("color", "colour must be >= 0"));
    }
    for (s, v) in [
        ("intensity", intensity),
        ("radius", size[0]),
        ("width", size[1]),
        ("height", size[2]),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(NodeError::invalid(
                s,
                format!("{v} must be finite and >= 0"),
            ));
        }
    }
    let path: String = ctx.input("path")?;
    if path.trim_matches('/').is_empty() {
        return Err(NodeError::invalid("path", "the light needs a prim name"));
    }
    let file: String = ctx.input("file")?;
    let light = framework_light(ty, &path, position, rotate, c.0, intensity, size, &file);
    let stage = Stage {
        lights: vec![light],
        ..Default::default()
    };
    ctx.set_output("layer", write_stage(&stage));
    Ok(())
}

fn declare_read(b: &mut NodeBuilder) {
    b.doc("Reads a USDA file's meshes, points, lights and camera as a layer (Framework3D's comp_read_usd).");
    b.add_input::<String>("path")
        .file_in()
        .doc("USDA file, relative to the graph's folder.");
    b.add_output::<String>("layer")
        .doc("The file's prims as a USDA layer (transforms applied).");
}

fn execute_read(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let p: String = ctx.input("path")?;
    let path = ctx.input_path(&p);
    let text = std::fs::read_to_string(&path).map_err(|e| NodeError::io(&path, e).at("path"))?;
    let stage = read_stage(&text)
        .map_err(|e| NodeError::invalid("path", format!("{}: {e}", path.display())))?;
    ctx.log(format!(
        "{} meshes, {} point clouds, {} lights",
        stage.meshes.len(),
        stage.points.len(),
        stage.lights.len()
    ));
    ctx.set_output("layer", write_stage(&stage));
    Ok(())
}

fn declare_merge(b: &mut NodeBuilder) {
    b.doc(
        "Puts a layer on the stage under /Reference/<path> (Framework3D's comp_merge_to_global).",
    );
    b.add_input::<String>("layer")
        .doc("A USDA layer (from stage_read).");
    b.add_input::<String>("path")
        .default("Scene")
        .doc("Where the layer goes: /Reference/<path>.");
    b.add_output::<String>("layer")
        .doc("The layer's prims under /Reference/<path>.");
}

fn execute_merge(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let text: String = ctx.input("layer")?;
    let path: String = ctx.input("path")?;
    let name = path.trim_matches('/');
    if name.is_empty() {
        return Err(NodeError::invalid("path", "the layer needs a prim path"));
    }
    let mut stage =
        read_stage(&text).map_err(|e| NodeError::invalid("layer", format!("not a stage: {e}")))?;
    let prefix: Vec<String> = name.split('/').map(usd_identifier).collect();
    stage.reroot(&format!("/Reference/{}", prefix.join("/")));
    ctx.set_output("layer", write_stage(&stage));
    Ok(())
}

/// Registers `stage_light`, `stage_read` and `stage_merge`.
pub fn register(r: &mut Registry) {
    r.add("stage_light", declare_light, execute_light);
    r.add("stage_read", declare_read, execute_read);
    r.add("stage_merge", declare_merge, execute_merge);
}
