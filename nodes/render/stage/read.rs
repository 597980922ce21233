//! Reading a USDA layer into a `Stage`: every `Mesh` (through the mesh domain's reader, world
//! transform applied), `Points`, UsdLux light (`SphereLight`, `DistantLight`, `DomeLight`,
//! `RectLight`) and the first `Camera`, depth first. A mesh without faces (what Write USD of
//! particles gives) becomes a point cloud. Light attributes are read with or without the
//! `inputs:` prefix (USD before and after 21.02). Errors name the line.

use super::model::{LightKind, Stage, StageCamera, StageLight, StagePoints, UpAxis};
use cgnodes_formats::usda::access::{floats, num, tuple_n, tuples};
use cgnodes_formats::usda::layer::{parse_usda, UsdLayer, UsdPrim, UsdValue};
use cgnodes_formats::usda::read::read_mesh_chain;
use cgnodes_formats::usda::transform::{transform_points, world_transform};
use cgnodes_formats::usda::UsdaError;

/// The diameter given to points without `widths`: the spacing they would have if spread
/// evenly through their bounding box, `(volume / n)^(1/3)`, at most a tenth of the box's
/// diagonal (0.04 m for hw9's 15,625 particles in a 1 m cube; Framework3D's particle
/// radius is 0.025 m).
pub fn default_width(points: &[[f64; 3]]) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let ext: Vec<f64> = (0..3).map(|k| (hi[k] - lo[k]).max(0.0)).collect();
    let diag = (ext.iter().map(|e| e * e).sum::<f64>()).sqrt();
    if points.len() < 2 || diag.is_nan() || diag <= 0.0 {
        return 0.05;
    }
    // Flat or thin clouds: measure the volume with each extent at least 1 % of the diagonal.
    let vol: f64 = ext.iter().map(|e| e.max(0.01 * diag)).product();
    (vol / points.len() as f64).cbrt().min(0.1 * diag)
}

/// Why a layer is not a stage: its syntax, or a prim (by path) that cannot be read.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StageError {
    /// The layer does not parse.
    #[error("{0}")]
    Layer(#[from] UsdaError),
    /// A mesh, point cloud, light or camera prim that cannot be read.
    #[error("prim '{path}': {message}")]
    Prim {
        /// The prim's path.
        path: String,
        /// What is wrong with it (with the layer's line where known).
        message: String,
    },
}

/// A `StageError` about prim `p`.
fn at(p: &UsdPrim) -> impl Fn(&dyn std::fmt::Display) -> StageError + '_ {
    move |e| StageError::Prim {
        path: p.path.clone(),
        message: e.to_string(),
    }
}

fn attr_num(p: &UsdPrim, names: &[&str], default: f64) -> Result<f64, UsdaError> {
    for n in names {
        if let Some(a) = p.attr(n) {
            if let Some(v) = &a.value {
                return num(v, a.line);
            }
        }
    }
    Ok(default)
}

fn attr_color(p: &UsdPrim, names: &[&str]) -> Result<[f64; 3], UsdaError> {
    for n in names {
        if let Some(a) = p.attr(n) {
            if let Some(v) = &a.value {
                return tuple_n::<3>(v, a.line, n);
            }
        }
    }
    Ok([1.0; 3])
}

fn attr_text(p: &UsdPrim, names: &[&str]) -> String {
    for n in names {
        if let Some(UsdValue::Str(s) | UsdValue::Ident(s)) =
            p.attr(n).and_then(|a| a.value.as_ref())
        {
            return s.clone();
        }
    }
    String::new()
}

/// A `Mesh` prim: a mesh, or a point cloud when it has no faces (Write USD of particles).
fn read_mesh(layer: &UsdLayer, chain: &[&UsdPrim], stage: &mut Stage) -> Result<(), StageError> {
    let p = chain[chain.len() - 1];
    let mesh = read_mesh_chain(layer, chain, true).map_err(|e| at(p)(&e))?;
    if mesh.num_faces() == 0 {
        let w = default_width(&mesh.positions);
        let colors = mesh.colors.as_ref().map(|c| c.values.clone());
        let colors = colors.filter(|c| c.len() == mesh.positions.len());
        stage.points.push(StagePoints {
            path: p.path.clone(),
            points: mesh.positions,
            widths: vec![w],
            colors,
        });
    } else {
        stage.meshes.push(super::model::StageMesh {
            path: p.path.clone(),
            mesh,
        });
    }
    Ok(())
}

/// A `Points` prim: world positions, widths scaled with the prim, optional colours.
fn read_points(chain: &[&UsdPrim]) -> Result<StagePoints, StageError> {
    let p = chain[chain.len() - 1];
    let at = at(p);
    let a = p
        .attr("points")
        .ok_or_else(|| at(&"a Points prim needs 'points'"))?;
    let mut pts = tuples::<3>(a).map_err(|e| at(&e))?;
    if pts.iter().flatten().any(|x| !x.is_finite()) {
        return Err(at(&"'points' holds a value that is not finite"));
    }
    let m = world_transform(chain).map_err(|e| at(&e))?;
    transform_points(&m, &mut pts);
    let mut widths = match p.attr("widths") {
        Some(w) => floats(w).map_err(|e| at(&e))?,
        None => vec![default_width(&pts)],
    };
    if widths.len() != 1 && widths.len() != pts.len() {
        return Err(at(&format!(
            "'widths' has {} values for {} points",
            widths.len(),
            pts.len()
        )));
    }
    if widths.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
        return Err(at(&"'widths' must be finite and >= 0"));
    }
    // A uniform scale of the prim scales the widths too.
    let s = m.fixed_view::<3, 3>(0, 0).determinant().abs().cbrt();
    if s.is_finite() && s > 0.0 {
        widths.iter_mut().for_each(|w| *w *= s);
    }
    let colors = match p.attr("primvars:displayColor") {
        Some(c) => {
            let c = tuples::<3>(c).map_err(|e| at(&e))?;
            if c.len() != 1 && c.len() != pts.len() {
                return Err(at(&format!(
                    "'primvars:displayColor' has {} values for {} points",
                    c.len(),
                    pts.len()
                )));
            }
            Some(c)
        }
        None => None,
    };
    Ok(StagePoints {
        path: p.path.clone(),
        points: pts,
        widths,
        colors,
    })
}

/// A UsdLux light prim (`SphereLight`, `DistantLight`, `DomeLight`, `RectLight`).
fn read_light(chain: &[&UsdPrim]) -> Result<StageLight, StageError> {
    let p = chain[chain.len() - 1];
    let at = at(p);
    let n = |names: &[&str], d: f64| attr_num(p, names, d).map_err(|e| at(&e));
    let kind = match p.type_name.as_str() {
        "SphereLight" => LightKind::Sphere {
            radius: n(&["inputs:radius", "radius"], 0.5)?,
        },
        "DistantLight" => LightKind::Distant {
            angle: n(&["inputs:angle", "angle"], 0.53)?,
        },
        "DomeLight" => LightKind::Dome {
            file: attr_text(p, &["inputs:texture:file", "texture:file"]),
        },
        _ => LightKind::Rect {
            width: n(&["inputs:width", "width"], 1.0)?,
            height: n(&["inputs:height", "height"], 1.0)?,
        },
    };
    let color = attr_color(p, &["inputs:color", "color"]).map_err(|e| at(&e))?;
    let intensity = n(&["inputs:intensity", "intensity"], 1.0)?;
    if color
        .iter()
        .chain([&intensity])
        .any(|x| !x.is_finite() || *x < 0.0)
    {
        return Err(at(&"light colour and intensity must be finite and >= 0"));
    }
    Ok(StageLight {
        path: p.path.clone(),
        kind,
        color,
        intensity,
        transform: world_transform(chain).map_err(|e| at(&e))?,
    })
}

/// A `Camera` prim: its vertical field of view and clipping range.
fn read_camera(chain: &[&UsdPrim]) -> Result<StageCamera, StageError> {
    let p = chain[chain.len() - 1];
    let at = at(p);
    let focal = attr_num(p, &["focalLength"], 50.0).map_err(|e| at(&e))?;
    let aperture = attr_num(p, &["verticalAperture"], 15.2908).map_err(|e| at(&e))?;
    if !(focal > 0.0 && aperture > 0.0 && focal.is_finite() && aperture.is_finite()) {
        return Err(at(&"focalLength and verticalAperture must be > 0"));
    }
    let clipping = match p.attr("clippingRange").and_then(|a| a.value.as_ref()) {
        Some(v) => {
            let line = p.attr("clippingRange").map_or(0, |a| a.line);
            let c = tuple_n::<2>(v, line, "clippingRange").map_err(|e| at(&e))?;
            (c[0], c[1])
        }
        None => (1.0, 1e6),
    };
    Ok(StageCamera {
        path: p.path.clone(),
        transform: world_transform(chain).map_err(|e| at(&e))?,
        fov_deg: 2.0 * (aperture / (2.0 * focal)).atan().to_degrees(),
        clipping,
    })
}

/// Reads prim `p` (with `chain` its ancestors) and its children, depth first.
fn visit<'a>(
    layer: &'a UsdLayer,
    p: &'a UsdPrim,
    chain: &mut Vec<&'a UsdPrim>,
    stage: &mut Stage,
) -> Result<(), StageError> {
    chain.push(p);
    if p.specifier != "class" {
        match p.type_name.as_str() {
            "Mesh" => read_mesh(layer, chain, stage)?,
            "Points" => stage.points.push(read_points(chain)?),
            "SphereLight" | "DistantLight" | "DomeLight" | "RectLight" => {
                stage.lights.push(read_light(chain)?)
            }
            "Camera" if stage.camera.is_none() => stage.camera = Some(read_camera(chain)?),
            _ => {}
        }
    }
    for c in &p.children {
        visit(layer, c, chain, stage)?;
    }
    chain.pop();
    Ok(())
}

/// Reads a USDA layer's meshes, points, lights and camera.
pub fn read_stage(text: &str) -> Result<Stage, StageError> {
    let layer = parse_usda(text)?;
    let up = layer
        .meta
        .iter()
        .find(|(k, _)| k == "upAxis")
        .map(|(_, v)| v);
    let up_axis = match up {
        Some(UsdValue::Str(s) | UsdValue::Ident(s)) if s == "Z" => UpAxis::Z,
        _ => UpAxis::Y,
    };
    let mut stage = Stage {
        up_axis,
        ..Default::default()
    };
    let mut chain = Vec::new();
    for p in &layer.prims {
        visit(&layer, p, &mut chain, &mut stage)?;
    }
    Ok(stage)
}
