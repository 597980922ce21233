//! Writing a `Stage` as one USDA layer: prims nested by their paths (missing ancestors become
//! `Xform`s), meshes with points, faces, normals, `primvars:UVMap` and
//! `primvars:displayColor`, `Points` with `widths`, UsdLux lights with `inputs:*` attributes
//! and `xformOp:transform`, and a `Camera` with focal length and apertures. Numbers use
//! Rust's shortest round-trip formatting, so reading the layer back gives the same values.

use super::model::{LightKind, Stage, StageCamera, StageLight, StageMesh, StagePoints};
use cgnodes_api::types::{Attribute, Domain};
use cgnodes_formats::usda::transform::Mat4;
use cgnodes_formats::usda::usd_identifier;
use std::fmt::Write as _;

/// USD's default vertical aperture of a camera (mm); the focal length is set from the
/// field of view against it.
pub const VERTICAL_APERTURE: f64 = 15.2908;

struct Prim {
    name: String,
    ty: String,
    body: Vec<String>,
    children: Vec<Prim>,
}

fn insert(level: &mut Vec<Prim>, parts: &[String], ty: &str, body: Vec<String>) {
    let Some((first, rest)) = parts.split_first() else {
        return;
    };
    let i = match level.iter().position(|p| &p.name == first) {
        Some(i) => i,
        None => {
            level.push(Prim {
                name: first.clone(),
                ty: "Xform".into(),
                body: Vec::new(),
                children: Vec::new(),
            });
            level.len() - 1
        }
    };
    if rest.is_empty() {
        level[i].ty = ty.to_string();
        level[i].body = body;
    } else {
        insert(&mut level[i].children, rest, ty, body);
    }
}

fn emit(out: &mut String, p: &Prim, depth: usize) {
    let ind = "    ".repeat(depth);
    let _ = writeln!(out, "{ind}def {} \"{}\"\n{ind}{{", p.ty, p.name);
    for l in &p.body {
        let _ = writeln!(out, "{ind}    {l}");
    }
    for c in &p.children {
        emit(out, c, depth + 1);
    }
    let _ = writeln!(out, "{ind}}}");
}

fn tuples<const N: usize>(v: &[[f64; N]]) -> String {
    let items: Vec<String> = v
        .iter()
        .map(|t| {
            let c: Vec<String> = t.iter().map(|x| format!("{x}")).collect();
            format!("({})", c.join(", "))
        })
        .collect();
    format!("[{}]", items.join(", "))
}

fn list<T: std::fmt::Display>(v: &[T]) -> String {
    let items: Vec<String> = v.iter().map(|x| format!("{x}")).collect();
    format!("[{}]", items.join(", "))
}

fn interp(d: Domain) -> &'static str {
    match d {
        Domain::Vertex => "vertex",
        Domain::Corner => "faceVarying",
        Domain::Face => "uniform",
    }
}

fn primvar<const N: usize>(decl: &str, a: &Attribute<[f64; N]>) -> String {
    format!(
        "{decl} = {} (interpolation = \"{}\")",
        tuples(&a.values),
        interp(a.domain)
    )
}

fn matrix(m: &Mat4) -> Vec<String> {
    let rows: Vec<String> = (0..4)
        .map(|r| {
            format!(
                "({}, {}, {}, {})",
                m[(r, 0)],
                m[(r, 1)],
                m[(r, 2)],
                m[(r, 3)]
            )
        })
        .collect();
    vec![
        format!("matrix4d xformOp:transform = ({})", rows.join(", ")),
        "uniform token[] xformOpOrder = [\"xformOp:transform\"]".into(),
    ]
}

fn split(path: &str) -> Vec<String> {
    let parts: Vec<String> = path
        .split('/')
        .filter(|s| !s.is_empty())
        .map(usd_identifier)
        .collect();
    if parts.is_empty() {
        vec!["prim".into()]
    } else {
        parts
    }
}

/// The USDA text of `stage`.
pub fn write_stage(stage: &Stage) -> String {
    let mut roots: Vec<Prim> = Vec::new();
    for m in &stage.meshes {
        insert(&mut roots, &split(&m.path), "Mesh", mesh_body(m));
    }
    for p in &stage.points {
        insert(&mut roots, &split(&p.path), "Points", points_body(p));
    }
    for l in &stage.lights {
        let (ty, body) = light_prim(l);
        insert(&mut roots, &split(&l.path), ty, body);
    }
    if let Some(c) = &stage.camera {
        insert(&mut roots, &split(&c.path), "Camera", camera_body(c));
    }
    let up = match stage.up_axis {
        super::model::UpAxis::Y => "Y",
        super::model::UpAxis::Z => "Z",
    };
    let mut out = format!(
        "#usda 1.0\n(\n    doc = \"written by cgnodes\"\n    metersPerUnit = 1\n    upAxis = \"{up}\"\n)\n\n"
    );
    for r in &roots {
        emit(&mut out, r, 0);
    }
    out
}

/// The attributes of a `Mesh` prim: faces, points, and the normals, UVs and display colours
/// the mesh has, as primvars of their domain.
fn mesh_body(m: &StageMesh) -> Vec<String> {
    let g = &m.mesh;
    let mut body = vec![
        format!("int[] faceVertexCounts = {}", list(g.face_counts())),
        format!("int[] faceVertexIndices = {}", list(g.face_indices())),
        format!("point3f[] points = {}", tuples(&g.positions)),
    ];
    if let Some(n) = &g.normals {
        body.push(primvar("normal3f[] normals", n));
    }
    if let Some(uv) = &g.uvs {
        body.push(primvar("texCoord2f[] primvars:UVMap", uv));
    }
    if let Some(c) = &g.colors {
        body.push(primvar("color3f[] primvars:displayColor", c));
    }
    body.push("uniform token subdivisionScheme = \"none\"".into());
    body
}

/// The attributes of a `Points` prim: points, widths and display colours (constant when
/// one value is given for all points).
fn points_body(p: &StagePoints) -> Vec<String> {
    let mut body = vec![
        format!("point3f[] points = {}", tuples(&p.points)),
        format!(
            "float[] widths = {} (interpolation = \"{}\")",
            list(&p.widths),
            if p.widths.len() == 1 {
                "constant"
            } else {
                "vertex"
            }
        ),
    ];
    if let Some(c) = &p.colors {
        body.push(format!(
            "color3f[] primvars:displayColor = {} (interpolation = \"{}\")",
            tuples(c),
            if c.len() == 1 { "constant" } else { "vertex" }
        ));
    }
    body
}

/// The UsdLux prim type of a light and its attributes: colour, intensity, the kind's
/// `inputs:*` and the transform.
fn light_prim(l: &StageLight) -> (&'static str, Vec<String>) {
    let mut body = vec![
        format!(
            "color3f inputs:color = ({}, {}, {})",
            l.color[0], l.color[1], l.color[2]
        ),
        "float inputs:diffuse = 1".into(),
        format!("float inputs:intensity = {}", l.intensity),
    ];
    let ty = match &l.kind {
        LightKind::Sphere { radius } => {
            body.push(format!("float inputs:radius = {radius}"));
            "SphereLight"
        }
        LightKind::Distant { angle } => {
            body.push(format!("float inputs:angle = {angle}"));
            "DistantLight"
        }
        LightKind::Dome { file } => {
            if !file.is_empty() {
                body.push(format!(
                    "asset inputs:texture:file = @{}@",
                    file.replace('@', "")
                ));
            }
            "DomeLight"
        }
        LightKind::Rect { width, height } => {
            body.push(format!("float inputs:width = {width}"));
            body.push(format!("float inputs:height = {height}"));
            "RectLight"
        }
    };
    body.extend(matrix(&l.transform));
    (ty, body)
}

/// The attributes of a `Camera` prim: the focal length giving the field of view against
/// `VERTICAL_APERTURE`, the clipping range and the transform.
fn camera_body(c: &StageCamera) -> Vec<String> {
    let focal = VERTICAL_APERTURE / (2.0 * (0.5 * c.fov_deg.to_radians()).tan());
    let mut body = vec![
        format!("float focalLength = {focal}"),
        format!("float verticalAperture = {VERTICAL_APERTURE}"),
        format!(
            "float2 clippingRange = ({}, {})",
            c.clipping.0, c.clipping.1
        ),
    ];
    body.extend(matrix(&c.transform));
    body
}
