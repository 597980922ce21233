//! Writing a `Mesh` as a USDA layer Framework3D and `usdview` can open.

use cgnodes_api::prelude::*;
use std::io::Write;

fn interp_name(d: Domain) -> &'static str {
    match d {
        Domain::Vertex => "vertex",
        Domain::Corner => "faceVarying",
        Domain::Face => "uniform",
    }
}

fn write_tuples<const N: usize>(w: &mut dyn Write, v: &[[f64; N]]) -> std::io::Result<()> {
    write!(w, "[")?;
    for (i, t) in v.iter().enumerate() {
        if i > 0 {
            write!(w, ", ")?;
        }
        write!(w, "(")?;
        for (k, x) in t.iter().enumerate() {
            if k > 0 {
                write!(w, ", ")?;
            }
            write!(w, "{x}")?;
        }
        write!(w, ")")?;
    }
    write!(w, "]")
}

fn write_list<T: std::fmt::Display>(w: &mut dyn Write, v: &[T]) -> std::io::Result<()> {
    write!(w, "[")?;
    for (i, x) in v.iter().enumerate() {
        if i > 0 {
            write!(w, ", ")?;
        }
        write!(w, "{x}")?;
    }
    write!(w, "]")
}

/// A valid USD identifier made from `s` (letters, digits, `_`; not starting with a digit).
pub fn usd_identifier(s: &str) -> String {
    let mut out: String = s
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if out.is_empty() || out.as_bytes()[0].is_ascii_digit() {
        out.insert(0, '_');
    }
    out
}

/// Writes `mesh` as a USDA layer Framework3D (and `usdview`) can open: an `Xform` per path
/// element of `prim_path` around a `Mesh`, with points, faces, normals, `primvars:UVMap`,
/// `primvars:displayColor` and the named attributes as primvars. Floats are written with
/// Rust's shortest round-trip formatting, so reading the file back gives the same values.
pub fn write_usda(mesh: &Mesh, prim_path: &str, w: &mut dyn Write) -> std::io::Result<()> {
    let parts: Vec<String> = prim_path
        .split('/')
        .filter(|s| !s.is_empty())
        .map(usd_identifier)
        .collect();
    let parts = if parts.is_empty() {
        vec!["mesh".to_string(), "mesh".to_string()]
    } else {
        parts
    };
    writeln!(w, "#usda 1.0")?;
    writeln!(w, "(")?;
    writeln!(w, "    defaultPrim = \"{}\"", parts[0])?;
    writeln!(w, "    doc = \"written by cgnodes\"")?;
    writeln!(w, "    metersPerUnit = 1")?;
    writeln!(w, "    upAxis = \"Z\"")?;
    writeln!(w, ")")?;
    writeln!(w)?;
    let n = parts.len();
    for (d, p) in parts.iter().enumerate() {
        let ind = "    ".repeat(d);
        let ty = if d + 1 == n { "Mesh" } else { "Xform" };
        writeln!(w, "{ind}def {ty} \"{p}\"")?;
        writeln!(w, "{ind}{{")?;
    }
    let ind = "    ".repeat(n);
    write_mesh_body(mesh, &ind, w)?;
    writeln!(w, "{ind}uniform token subdivisionScheme = \"none\"")?;
    for d in (0..n).rev() {
        writeln!(w, "{}}}", "    ".repeat(d))?;
    }
    Ok(())
}

/// The `Mesh` prim's attributes, indented by `ind`: extent, topology, normals, points,
/// display colour, UVs, then the named attributes as primvars.
fn write_mesh_body(mesh: &Mesh, ind: &str, w: &mut dyn Write) -> std::io::Result<()> {
    let (lo, hi) = mesh.bounds();
    write!(w, "{ind}float3[] extent = ")?;
    write_tuples(w, &[lo, hi])?;
    writeln!(w)?;
    write!(w, "{ind}int[] faceVertexCounts = ")?;
    write_list(w, mesh.face_counts())?;
    writeln!(w)?;
    write!(w, "{ind}int[] faceVertexIndices = ")?;
    write_list(w, mesh.face_indices())?;
    writeln!(w)?;
    if let Some(nm) = &mesh.normals {
        write!(w, "{ind}normal3f[] normals = ")?;
        write_tuples(w, &nm.values)?;
        writeln!(
            w,
            " (\n{ind}    interpolation = \"{}\"\n{ind})",
            interp_name(nm.domain)
        )?;
    }
    write!(w, "{ind}point3f[] points = ")?;
    write_tuples(w, &mesh.positions)?;
    writeln!(w)?;
    if let Some(c) = &mesh.colors {
        write!(w, "{ind}color3f[] primvars:displayColor = ")?;
        write_tuples(w, &c.values)?;
        writeln!(
            w,
            " (\n{ind}    interpolation = \"{}\"\n{ind})",
            interp_name(c.domain)
        )?;
    }
    if let Some(uv) = &mesh.uvs {
        write!(w, "{ind}texCoord2f[] primvars:UVMap = ")?;
        write_tuples(w, &uv.values)?;
        writeln!(
            w,
            " (\n{ind}    interpolation = \"{}\"\n{ind})",
            interp_name(uv.domain)
        )?;
    }
    write_named_primvars(mesh, ind, w)
}

/// The mesh's named attributes as double/int primvars with their interpolation.
fn write_named_primvars(mesh: &Mesh, ind: &str, w: &mut dyn Write) -> std::io::Result<()> {
    for (name, a) in &mesh.attributes {
        let name = usd_identifier(name);
        let d = match a {
            AttributeData::Float(x) => {
                write!(w, "{ind}double[] primvars:{name} = ")?;
                write_list(w, &x.values)?;
                x.domain
            }
            AttributeData::Int(x) => {
                write!(w, "{ind}int[] primvars:{name} = ")?;
                write_list(w, &x.values)?;
                x.domain
            }
            AttributeData::Vec2(x) => {
                write!(w, "{ind}double2[] primvars:{name} = ")?;
                write_tuples(w, &x.values)?;
                x.domain
            }
            AttributeData::Vec3(x) => {
                write!(w, "{ind}double3[] primvars:{name} = ")?;
                write_tuples(w, &x.values)?;
                x.domain
            }
        };
        writeln!(
            w,
            " (\n{ind}    interpolation = \"{}\"\n{ind})",
            interp_name(d)
        )?;
    }
    Ok(())
}
