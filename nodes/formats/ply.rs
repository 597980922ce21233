//! Stanford PLY, ASCII and binary (little and big endian): vertices with optional normals,
//! UVs (`s,t`, `u,v` or `texture_u,texture_v`) and colours, faces as index lists, and
//! per-corner UVs as a face `texcoord` list (MeshLab's convention). Other elements and
//! properties are read and skipped.

use cgnodes_api::prelude::*;
use std::io::Write;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

#[derive(Clone, Debug)]
struct Prop {
    name: String,
    ty: Scalar,
    list_count: Option<Scalar>,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Prop>,
}

#[derive(Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    Le,
    Be,
}

/// Reads the values of a PLY body, one element instance at a time.
trait Source {
    fn scalar(&mut self, ty: Scalar) -> Result<f64, String>;
    /// Called at the start of each element instance (ASCII: moves to the next line).
    fn begin(&mut self) -> Result<(), String> {
        Ok(())
    }
    fn end(&mut self) -> Result<(), String> {
        Ok(())
    }
}

struct Binary<'a> {
    b: &'a [u8],
    i: usize,
    be: bool,
}

impl Source for Binary<'_> {
    fn scalar(&mut self, ty: Scalar) -> Result<f64, String> {
        let n = ty.size();
        if self.i + n > self.b.len() {
            return Err(format!("binary data ends early (at byte {})", self.i));
        }
        let mut a = [0u8; 8];
        a[..n].copy_from_slice(&self.b[self.i..self.i + n]);
        if self.be {
            a[..n].reverse();
        }
        self.i += n;
        Ok(match ty {
            Scalar::I8 => a[0] as i8 as f64,
            Scalar::U8 => a[0] as f64,
            Scalar::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(a),
        })
    }
}

struct Ascii<'a> {
    lines: std::iter::Peekable<std::iter::Enumerate<std::str::Lines<'a>>>,
    cur: Vec<&'a str>,
    pos: usize,
    line: usize,
    /// Lines before the body (the header), so errors give the file's line number.
    offset: usize,
}

impl Source for Ascii<'_> {
    fn begin(&mut self) -> Result<(), String> {
        loop {
            let (i, l) = self
                .lines
                .next()
                .ok_or("the file ends before all elements are read")?;
            self.line = i + 1 + self.offset;
            self.cur = l.split_whitespace().collect();
            self.pos = 0;
            if !self.cur.is_empty() {
                return Ok(());
            }
        }
    }
    fn scalar(&mut self, _ty: Scalar) -> Result<f64, String> {
        let s = self
            .cur
            .get(self.pos)
            .ok_or_else(|| format!("line {}: too few values", self.line))?;
        self.pos += 1;
        s.parse::<f64>()
            .map_err(|_| format!("line {}: '{s}' is not a number", self.line))
    }
    fn end(&mut self) -> Result<(), String> {
        if self.pos != self.cur.len() {
            return Err(format!(
                "line {}: {} values expected, {} found",
                self.line,
                self.pos,
                self.cur.len()
            ));
        }
        Ok(())
    }
}

/// Refuses element counts the body cannot hold, before anything is read or allocated
/// (issue 23): every instance takes at least its fixed-size values and list counts in a
/// binary body, and at least two bytes (a digit and a separator) per property in an ASCII
/// one. Overflowing totals count as too large.
fn check_counts(elements: &[Element], format: Format, body: usize) -> Result<(), String> {
    let mut need: u128 = 0;
    for el in elements {
        let per: u128 = el
            .props
            .iter()
            .map(|p| match format {
                Format::Ascii => 2,
                _ => p.list_count.unwrap_or(p.ty).size() as u128,
            })
            .sum();
        need = need.saturating_add(per.saturating_mul(el.count as u128));
        // The last value of an ASCII body may end the file without a separator.
        let slack = u128::from(format == Format::Ascii);
        if need > body as u128 + slack {
            return Err(format!(
                "element '{}' declares {} instances, more than the {body} bytes of data can hold",
                el.name, el.count
            ));
        }
    }
    Ok(())
}

/// Reads a PLY file (ASCII or binary). Errors give the header or body line (ASCII) or the
/// byte offset (binary).
pub fn read_ply(bytes: &[u8]) -> Result<Mesh, String> {
    if !bytes.starts_with(b"ply") {
        return Err("line 1: not a PLY file (it must start with 'ply')".into());
    }
    // Header: text up to and including "end_header\n".
    let end = bytes
        .windows(10)
        .position(|w| w == b"end_header")
        .ok_or("no 'end_header' line")?;
    let mut body = end + 10;
    while body < bytes.len() && bytes[body] != b'\n' {
        body += 1;
    }
    body += 1;
    let header = std::str::from_utf8(&bytes[..end]).map_err(|_| "header is not text")?;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for (i, l) in header.lines().enumerate() {
        let ln = i + 1;
        let w: Vec<&str> = l.split_whitespace().collect();
        match w.first().copied() {
            None | Some("ply") | Some("comment") | Some("obj_info") => {}
            Some("format") => {
                format = Some(match w.get(1).copied() {
                    Some("ascii") => Format::Ascii,
                    Some("binary_little_endian") => Format::Le,
                    Some("binary_big_endian") => Format::Be,
                    _ => return Err(format!("line {ln}: unknown format '{l}'")),
                })
            }
            Some("element") => {
                let (Some(name), Some(count)) = (w.get(1), w.get(2).and_then(|c| c.parse().ok()))
                else {
                    return Err(format!("line {ln}: malformed element '{l}'"));
                };
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| format!("line {ln}: property before any element"))?;
                let bad = || format!("line {ln}: malformed property '{l}'");
                let p = if w.get(1) == Some(&"list") {
                    Prop {
                        list_count: Some(w.get(2).and_then(|s| Scalar::parse(s)).ok_or_else(bad)?),
                        ty: w.get(3).and_then(|s| Scalar::parse(s)).ok_or_else(bad)?,
                        name: w.get(4).ok_or_else(bad)?.to_string(),
                    }
                } else {
                    Prop {
                        list_count: None,
                        ty: w.get(1).and_then(|s| Scalar::parse(s)).ok_or_else(bad)?,
                        name: w.get(2).ok_or_else(bad)?.to_string(),
                    }
                };
                el.props.push(p);
            }
            Some(_) => return Err(format!("line {ln}: unknown header line '{l}'")),
        }
    }
    let format = format.ok_or("the header has no 'format' line")?;
    check_counts(&elements, format, bytes.len().saturating_sub(body))?;
    let header_lines = header.lines().count() + 1;
    let text_body;
    let mut src: Box<dyn Source> = match format {
        Format::Ascii => {
            text_body = std::str::from_utf8(&bytes[body.min(bytes.len())..])
                .map_err(|_| "ASCII body is not text")?;
            Box::new(Ascii {
                lines: text_body.lines().enumerate().peekable(),
                cur: Vec::new(),
                pos: 0,
                line: 0,
                offset: header_lines,
            })
        }
        f => Box::new(Binary {
            b: bytes,
            i: body,
            be: f == Format::Be,
        }),
    };
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    let mut colors = Vec::new();
    let mut corner_uvs = Vec::new();
    let mut fc = Vec::new();
    let mut fi = Vec::new();
    for el in &elements {
        let find = |n: &[&str]| el.props.iter().position(|p| n.contains(&p.name.as_str()));
        let (px, py, pz) = (find(&["x"]), find(&["y"]), find(&["z"]));
        let (nx, ny, nz) = (find(&["nx"]), find(&["ny"]), find(&["nz"]));
        let (tu, tv) = (
            find(&["s", "u", "texture_u", "texture_s"]),
            find(&["t", "v", "texture_v", "texture_t"]),
        );
        let (cr, cg, cb) = (
            find(&["red", "r", "diffuse_red"]),
            find(&["green", "g", "diffuse_green"]),
            find(&["blue", "b", "diffuse_blue"]),
        );
        let fv = find(&["vertex_indices", "vertex_index"]);
        let ft = find(&["texcoord"]);
        let is_vertex = el.name == "vertex";
        let is_face = el.name == "face";
        if is_vertex && (px.is_none() || py.is_none() || pz.is_none()) {
            return Err("the vertex element has no x, y, z properties".into());
        }
        if is_face && fv.is_none() {
            return Err("the face element has no vertex_indices list".into());
        }
        if el.props.is_empty() && el.count > 0 {
            // Nothing to read per instance: a binary body would be looped over `count` times
            // without consuming a byte.
            return Err(format!(
                "element '{}' declares {} instances but no properties",
                el.name, el.count
            ));
        }
        let mut vals: Vec<Vec<f64>> = vec![Vec::new(); el.props.len()];
        for k in 0..el.count {
            src.begin()?;
            for v in vals.iter_mut() {
                v.clear();
            }
            for (pi, p) in el.props.iter().enumerate() {
                match p.list_count {
                    None => vals[pi].push(src.scalar(p.ty)?),
                    Some(ct) => {
                        let n = src.scalar(ct)?;
                        if n < 0.0 || n.fract() != 0.0 {
                            return Err(format!("{} {k}: bad list length {n}", el.name));
                        }
                        for _ in 0..n as usize {
                            vals[pi].push(src.scalar(p.ty)?);
                        }
                    }
                }
            }
            src.end()?;
            // A property declared as a list may hold no value: read the first one, if any.
            let first = |i: usize| vals[i].first().copied();
            let g = |i: Option<usize>| i.and_then(first);
            if is_vertex {
                let (Some(x), Some(y), Some(z)) = (g(px), g(py), g(pz)) else {
                    return Err(format!("vertex {k}: x, y and z need one value each"));
                };
                let p = [x, y, z];
                if p.iter().any(|x| !x.is_finite()) {
                    return Err(format!("vertex {k} has a non-finite coordinate {p:?}"));
                }
                positions.push(p);
                if let (Some(a), Some(b), Some(c)) = (g(nx), g(ny), g(nz)) {
                    normals.push([a, b, c]);
                }
                if let (Some(a), Some(b)) = (g(tu), g(tv)) {
                    uvs.push([a, b]);
                }
                if let (Some(r), Some(gg), Some(b)) = (cr, cg, cb) {
                    let scale = if el.props[r].ty == Scalar::U8 {
                        1.0 / 255.0
                    } else {
                        1.0
                    };
                    if let (Some(r), Some(gg), Some(b)) = (first(r), first(gg), first(b)) {
                        colors.push([r * scale, gg * scale, b * scale]);
                    }
                }
            } else if is_face {
                let idx = &vals[fv.unwrap_or(0)];
                if idx.len() < 3 {
                    return Err(format!("face {k} is degenerate: {} corners", idx.len()));
                }
                // Large faces find repeats through a set: a scan per corner was O(k²).
                let mut seen = std::collections::HashSet::new();
                for (c, &i) in idx.iter().enumerate() {
                    // `i as usize` would turn NaN into 0 and 1.5 into 1: only whole numbers.
                    if !(i >= 0.0 && i.fract() == 0.0 && i < positions.len() as f64) {
                        return Err(format!(
                            "face {k} refers to vertex {i}, but there are {} vertices",
                            positions.len()
                        ));
                    }
                    let repeated = if idx.len() > 32 {
                        !seen.insert(i as u32)
                    } else {
                        idx[..c].contains(&i)
                    };
                    if repeated {
                        return Err(format!("face {k} is degenerate: vertex {i} appears twice"));
                    }
                    fi.push(i as u32);
                }
                fc.push(idx.len() as u32);
                if let Some(t) = ft {
                    let t = &vals[t];
                    if t.len() != 2 * idx.len() {
                        return Err(format!(
                            "face {k}: texcoord list has {} values for {} corners",
                            t.len(),
                            idx.len()
                        ));
                    }
                    corner_uvs.extend(t.chunks_exact(2).map(|c| [c[0], c[1]]));
                }
            }
        }
    }
    let nv = positions.len();
    let mut mesh = Mesh::new(positions, fc, fi).map_err(|e| e.to_string())?;
    if normals.len() == nv && nv > 0 {
        mesh.normals = Some(Attribute {
            domain: Domain::Vertex,
            values: normals,
        });
    }
    if !corner_uvs.is_empty() {
        mesh.uvs = Some(Attribute {
            domain: Domain::Corner,
            values: corner_uvs,
        });
    } else if uvs.len() == nv && nv > 0 {
        mesh.uvs = Some(Attribute {
            domain: Domain::Vertex,
            values: uvs,
        });
    }
    if colors.len() == nv && nv > 0 {
        mesh.colors = Some(Attribute {
            domain: Domain::Vertex,
            values: colors,
        });
    }
    Ok(mesh)
}

/// The first lines of every PLY file written here: magic, format (ASCII or binary little
/// endian) and one comment line.
fn write_preamble(w: &mut dyn Write, binary: bool, comment: &str) -> std::io::Result<()> {
    let fmt = if binary {
        "binary_little_endian"
    } else {
        "ascii"
    };
    writeln!(w, "ply\nformat {fmt} 1.0\ncomment {comment}")
}

/// One `float` column of a PLY point cloud: its value at each point.
pub type PlyColumn<'a> = Box<dyn Fn(usize) -> f64 + 'a>;

/// Writes a PLY point cloud of `n` points, a `vertex` element only, with one single-precision
/// `float` property per column (`props[k]` names `columns[k]`), ASCII or binary little endian.
/// For particle frames (ParaView, Blender, Houdini read them); meshes use `write_ply`.
pub fn write_ply_points(
    w: &mut dyn Write,
    comment: &str,
    n: usize,
    props: &[String],
    columns: &[PlyColumn<'_>],
    binary: bool,
) -> std::io::Result<()> {
    write_preamble(w, binary, comment)?;
    writeln!(w, "element vertex {n}")?;
    for p in props {
        writeln!(w, "property float {p}")?;
    }
    writeln!(w, "end_header")?;
    let mut buf = Vec::with_capacity(n * columns.len() * 4);
    for i in 0..n {
        if binary {
            for c in columns {
                buf.extend_from_slice(&(c(i) as f32).to_le_bytes());
            }
        } else {
            let line: Vec<String> = columns.iter().map(|c| format!("{}", c(i) as f32)).collect();
            buf.extend_from_slice(line.join(" ").as_bytes());
            buf.push(b'\n');
        }
    }
    w.write_all(&buf)
}

/// The type of a list's length in a written PLY file: the narrowest that holds every length.
#[derive(Clone, Copy)]
enum ListCount {
    U8,
    U16,
    U32,
}

impl ListCount {
    fn holding(max: usize) -> ListCount {
        if max <= u8::MAX as usize {
            ListCount::U8
        } else if max <= u16::MAX as usize {
            ListCount::U16
        } else {
            ListCount::U32
        }
    }
    fn name(self) -> &'static str {
        match self {
            ListCount::U8 => "uchar",
            ListCount::U16 => "ushort",
            ListCount::U32 => "uint",
        }
    }
    /// Writes `n` little endian in this type (`holding` chose a type that fits it).
    fn write(self, w: &mut dyn Write, n: usize) -> std::io::Result<()> {
        match self {
            ListCount::U8 => w.write_all(&[n as u8]),
            ListCount::U16 => w.write_all(&(n as u16).to_le_bytes()),
            ListCount::U32 => w.write_all(&(n as u32).to_le_bytes()),
        }
    }
}

/// Writes a PLY file: ASCII, or binary little endian with double-precision vertices.
/// Per-vertex normals, UVs and colours become vertex properties; per-corner UVs a face
/// `texcoord` list.
pub fn write_ply(mesh: &Mesh, binary: bool, w: &mut dyn Write) -> std::io::Result<()> {
    let vn = mesh.normals.as_ref().filter(|a| a.domain == Domain::Vertex);
    let vuv = mesh.uvs.as_ref().filter(|a| a.domain == Domain::Vertex);
    let cuv = mesh.uvs.as_ref().filter(|a| a.domain == Domain::Corner);
    let vc = mesh.colors.as_ref().filter(|a| a.domain == Domain::Vertex);
    write_preamble(w, binary, "written by cgnodes")?;
    writeln!(w, "element vertex {}", mesh.num_vertices())?;
    let mut names: Vec<&str> = vec!["x", "y", "z"];
    if vn.is_some() {
        names.extend(["nx", "ny", "nz"]);
    }
    if vuv.is_some() {
        names.extend(["s", "t"]);
    }
    if vc.is_some() {
        names.extend(["red", "green", "blue"]);
    }
    for n in &names {
        writeln!(w, "property double {n}")?;
    }
    // List counts in the narrowest type that holds the largest face (issue 23: a uchar count
    // clamped to 255 while every index was written made faces past 255 corners, or 127 with
    // per-corner UVs, corrupt the rest of the file). Usual meshes keep `uchar`.
    let widest = mesh.face_counts().iter().copied().max().unwrap_or(0) as usize;
    let idx_ty = ListCount::holding(widest);
    let uv_ty = ListCount::holding(2 * widest);
    writeln!(w, "element face {}", mesh.num_faces())?;
    writeln!(w, "property list {} int vertex_indices", idx_ty.name())?;
    if cuv.is_some() {
        writeln!(w, "property list {} double texcoord", uv_ty.name())?;
    }
    writeln!(w, "end_header")?;
    for v in 0..mesh.num_vertices() {
        let mut row: Vec<f64> = mesh.positions[v].to_vec();
        if let Some(a) = vn {
            row.extend(a.values[v]);
        }
        if let Some(a) = vuv {
            row.extend(a.values[v]);
        }
        if let Some(a) = vc {
            row.extend(a.values[v]);
        }
        if binary {
            for x in row {
                w.write_all(&x.to_le_bytes())?;
            }
        } else {
            let s: Vec<String> = row.iter().map(|x| x.to_string()).collect();
            writeln!(w, "{}", s.join(" "))?;
        }
    }
    let starts = mesh.face_starts();
    for (f, face) in mesh.faces().enumerate() {
        let n = face.len();
        let uv = cuv.map(|a| &a.values[starts[f] as usize..starts[f + 1] as usize]);
        if binary {
            idx_ty.write(w, n)?;
            for &v in face {
                w.write_all(&(v as i32).to_le_bytes())?;
            }
            if let Some(uv) = uv {
                uv_ty.write(w, 2 * n)?;
                for t in uv {
                    w.write_all(&t[0].to_le_bytes())?;
                    w.write_all(&t[1].to_le_bytes())?;
                }
            }
        } else {
            write!(w, "{n}")?;
            for v in face {
                write!(w, " {v}")?;
            }
            if let Some(uv) = uv {
                write!(w, " {}", 2 * n)?;
                for t in uv {
                    write!(w, " {} {}", t[0], t[1])?;
                }
            }
            writeln!(w)?;
        }
    }
    Ok(())
}

#[cfg(test)]
#[path = "ply_tests.rs"]
mod tests;
