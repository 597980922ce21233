//! `points_save`: writes particles as a PLY point cloud (ascii or binary little endian),
//! with every scalar attribute as a `float` property and every vector attribute as three
//! (`name_x`, `name_y`, `name_z`), so ParaView, Blender or Houdini can read the frames.

use cgnodes_api::prelude::*;
use std::io::Write;

/// Writes `points` as PLY to `w`.
pub fn write_ply(points: &Points, binary: bool, w: &mut dyn Write) -> std::io::Result<()> {
    let n = points.positions.len();
    let mut props: Vec<String> = vec!["x".into(), "y".into(), "z".into()];
    let mut cols: Vec<cgnodes_formats::ply::PlyColumn<'_>> = vec![
        Box::new(|i| points.positions[i][0]),
        Box::new(|i| points.positions[i][1]),
        Box::new(|i| points.positions[i][2]),
    ];
    for (name, vals) in &points.scalars {
        if vals.len() == n {
            props.push(clean(name));
            cols.push(Box::new(move |i| vals[i]));
        }
    }
    for (name, vals) in &points.vectors {
        if vals.len() == n {
            for (a, s) in ["x", "y", "z"].iter().enumerate() {
                props.push(format!("{}_{s}", clean(name)));
                cols.push(Box::new(move |i| vals[i][a]));
            }
        }
    }
    cgnodes_formats::ply::write_ply_points(w, "cgnodes points_save", n, &props, &cols, binary)
}

fn clean(name: &str) -> String {
    name.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

/// The PLY encoding of the `format` socket.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PlyFormat {
    /// Binary little endian.
    Binary,
    /// Text.
    Ascii,
}

impl Choice for PlyFormat {
    const CHOICES: &'static [(&'static str, Self)] =
        &[("binary", PlyFormat::Binary), ("ascii", PlyFormat::Ascii)];
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Writes particles as a PLY point cloud with their attributes.");
    b.sink();
    b.add_input::<Points>("points");
    b.add_input::<String>("path")
        .file_out()
        .doc("Output .ply file; `{frame}` or `{frame:04}` is replaced by the frame.");
    b.add_choice::<PlyFormat>("format")
        .doc("PLY encoding (binary little endian or ascii).");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let pts: Arc<Points> = ctx.input("points")?;
    let p: String = ctx.input("path")?;
    let binary = ctx.choice::<PlyFormat>("format")? == PlyFormat::Binary;
    let path = ctx.output_path("path", &p)?;
    if path.extension().and_then(|e| e.to_str()) != Some("ply") {
        return Err(NodeError::invalid(
            "path",
            format!("'{p}' should end in .ply"),
        ));
    }
    ctx.write_with(&path, |w| write_ply(&pts, binary, w))
}

/// Registers `points_save`.
pub fn register(r: &mut Registry) {
    r.add("points_save", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ply_header_and_body() {
        let mut pts = Points {
            dim: 2,
            positions: vec![[1.0, 2.0, 0.0], [3.0, 4.5, 0.0]],
            ..Default::default()
        };
        pts.scalars.insert("density".into(), vec![1000.0, 999.5]);
        pts.vectors
            .insert("velocity".into(), vec![[0.0, -1.0, 0.0], [0.5, 0.0, 0.0]]);
        let mut a = Vec::new();
        write_ply(&pts, false, &mut a).unwrap();
        let s = String::from_utf8(a).unwrap();
        assert!(s.contains("element vertex 2\n"));
        assert!(s.contains("property float velocity_z\nend_header\n"));
        assert!(s.ends_with("3 4.5 0 999.5 0.5 0 0\n"), "{s}");
        let mut b = Vec::new();
        write_ply(&pts, true, &mut b).unwrap();
        let hdr = b.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
        let body = b.len() - hdr;
        assert_eq!(body, 2 * 7 * 4);
    }
}
