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

/// Why a PLY file could not be read: the header line, body line (ASCII), byte offset
/// (binary) or element instance at fault.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PlyError {
    /// The file does not start with the `ply` magic.
    #[error("line 1: not a PLY file (it must start with 'ply')")]
    NotPly,
    /// The header never ends.
    #[error("no 'end_header' line")]
    NoEndHeader,
    /// The header is not UTF-8.
    #[error("header is not text")]
    HeaderNotText,
    /// A header line that cannot be read, by its 1-based number and a description.
    #[error("line {line}: {what} '{text}'")]
    Header {
        /// The header line's 1-based number.
        line: usize,
        /// What is wrong: "unknown format", "malformed element", ...
        what: &'static str,
        /// The line's text.
        text: String,
    },
    /// A `property` line before any `element` line.
    #[error("line {0}: property before any element")]
    PropertyBeforeElement(usize),
    /// The header has no `format` line.
    #[error("the header has no 'format' line")]
    NoFormat,
    /// An element count larger than the body could hold.
    #[error(
        "element '{element}' declares {count} instances, more than the {body} bytes of data can hold"
    )]
    TooManyInstances {
        /// The element's name.
        element: String,
        /// Its declared count.
        count: usize,
        /// The body's size in bytes.
        body: usize,
    },
    /// An element with instances but no property to read.
    #[error("element '{element}' declares {count} instances but no properties")]
    NoProperties {
        /// The element's name.
        element: String,
        /// Its declared count.
        count: usize,
    },
    /// The ASCII body is not UTF-8.
    #[error("ASCII body is not text")]
    BodyNotText,
    /// The binary body ends inside a value.
    #[error("binary data ends early (at byte {0})")]
    BinaryEnds(usize),
    /// The ASCII body ends before the last element instance.
    #[error("the file ends before all elements are read")]
    AsciiEnds,
    /// An ASCII line has fewer values than its element's properties.
    #[error("line {0}: too few values")]
    TooFewValues(usize),
    /// An ASCII value is not a number.
    #[error("line {line}: '{text}' is not a number")]
    NotANumber {
        /// The file's 1-based line.
        line: usize,
        /// The token.
        text: String,
    },
    /// An ASCII line has more values than its element's properties.
    #[error("line {line}: {expected} values expected, {found} found")]
    ValueCount {
        /// The file's 1-based line.
        line: usize,
        /// Values the properties read.
        expected: usize,
        /// Values on the line.
        found: usize,
    },
    /// The vertex element lacks a coordinate property.
    #[error("the vertex element has no x, y, z properties")]
    NoCoordinates,
    /// The face element lacks its index list.
    #[error("the face element has no vertex_indices list")]
    NoIndices,
    /// A list length that is negative or fractional.
    #[error("{element} {index}: bad list length {len}")]
    ListLength {
        /// The element's name.
        element: String,
        /// The instance.
        index: usize,
        /// The length read.
        len: f64,
    },
    /// A vertex whose x, y or z list is empty.
    #[error("vertex {0}: x, y and z need one value each")]
    EmptyCoordinate(usize),
    /// A vertex with a NaN or infinite coordinate.
    #[error("vertex {vertex} has a non-finite coordinate {position:?}")]
    NonFinite {
        /// The vertex.
        vertex: usize,
        /// Its coordinates.
        position: [f64; 3],
    },
    /// A face of fewer than three corners.
    #[error("face {face} is degenerate: {corners} corners")]
    TooFewCorners {
        /// The face.
        face: usize,
        /// Its corner count.
        corners: usize,
    },
    /// A face index that is not a vertex.
    #[error("face {face} refers to vertex {index}, but there are {vertices} vertices")]
    BadIndex {
        /// The face.
        face: usize,
        /// The index read.
        index: f64,
        /// Vertices read so far.
        vertices: usize,
    },
    /// A face naming a vertex twice.
    #[error("face {face} is degenerate: vertex {vertex} appears twice")]
    RepeatedVertex {
        /// The face.
        face: usize,
        /// The repeated vertex.
        vertex: f64,
    },
    /// A face whose texcoord list is not two values per corner.
    #[error("face {face}: texcoord list has {values} values for {corners} corners")]
    Texcoords {
        /// The face.
        face: usize,
        /// Values in the list.
        values: usize,
        /// The face's corners.
        corners: usize,
    },
    /// The faces and vertices do not make a mesh (`Mesh::new`).
    #[error("{0}")]
    Mesh(String),
}

/// Reads the values of a PLY body, one element instance at a time.
trait Source {
    fn scalar(&mut self, ty: Scalar) -> Result<f64, PlyError>;
    /// Called at the start of each element instance (ASCII: moves to the next line).
    fn begin(&mut self) -> Result<(), PlyError> {
        Ok(())
    }
    fn end(&mut self) -> Result<(), PlyError> {
        Ok(())
    }
}

struct Binary<'a> {
    b: &'a [u8],
    i: usize,
    be: bool,
}

impl Source for Binary<'_> {
    fn scalar(&mut self, ty: Scalar) -> Result<f64, PlyError> {
        let n = ty.size();
        if self.i + n > self.b.len() {
            return Err(PlyError::BinaryEnds(self.i));
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
    fn begin(&mut self) -> Result<(), PlyError> {
        loop {
            let (i, l) = self.lines.next().ok_or(PlyError::AsciiEnds)?;
            self.line = i + 1 + self.offset;
            self.cur = l.split_whitespace().collect();
            self.pos = 0;
            if !self.cur.is_empty() {
                return Ok(());
            }
        }
    }
    fn scalar(&mut self, _ty: Scalar) -> Result<f64, PlyError> {
        let s = self
            .cur
            .get(self.pos)
            .ok_or(PlyError::TooFewValues(self.line))?;
        self.pos += 1;
        s.parse::<f64>().map_err(|_| PlyError::NotANumber {
            line: self.line,
            text: s.to_string(),
        })
    }
    fn end(&mut self) -> Result<(), PlyError> {
        if self.pos != self.cur.len() {
            return Err(PlyError::ValueCount {
                line: self.line,
                expected: self.pos,
                found: self.cur.len(),
            });
        }
        Ok(())
    }
}

/// Refuses element counts the body cannot hold, before anything is read or allocated
/// (issue 23): every instance takes at least its fixed-size values and list counts in a
/// binary body, and at least two bytes (a digit and a separator) per property in an ASCII
/// one. Overflowing totals count as too large.
fn check_counts(elements: &[Element], format: Format, body: usize) -> Result<(), PlyError> {
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
            return Err(PlyError::TooManyInstances {
                element: el.name.clone(),
                count: el.count,
                body,
            });
        }
    }
    Ok(())
}

/// A PLY header: the body's format and elements, where the body starts (byte) and how
/// many lines precede it.
struct Header {
    format: Format,
    elements: Vec<Element>,
    body: usize,
    lines: usize,
}

/// One `property` line (`w` its words) as a property.
fn parse_property(w: &[&str], ln: usize, l: &str) -> Result<Prop, PlyError> {
    let bad = || PlyError::Header {
        line: ln,
        what: "malformed property",
        text: l.to_string(),
    };
    let scalar = |i: usize| w.get(i).and_then(|s| Scalar::parse(s)).ok_or_else(bad);
    Ok(if w.get(1) == Some(&"list") {
        Prop {
            list_count: Some(scalar(2)?),
            ty: scalar(3)?,
            name: w.get(4).ok_or_else(bad)?.to_string(),
        }
    } else {
        Prop {
            list_count: None,
            ty: scalar(1)?,
            name: w.get(2).ok_or_else(bad)?.to_string(),
        }
    })
}

/// Reads the header up to `end_header` and checks the declared counts against the body.
fn parse_header(bytes: &[u8]) -> Result<Header, PlyError> {
    if !bytes.starts_with(b"ply") {
        return Err(PlyError::NotPly);
    }
    // Header: text up to and including "end_header\n".
    let end = bytes
        .windows(10)
        .position(|w| w == b"end_header")
        .ok_or(PlyError::NoEndHeader)?;
    let mut body = end + 10;
    while body < bytes.len() && bytes[body] != b'\n' {
        body += 1;
    }
    body += 1;
    let header = std::str::from_utf8(&bytes[..end]).map_err(|_| PlyError::HeaderNotText)?;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for (i, l) in header.lines().enumerate() {
        let ln = i + 1;
        let bad = |what| PlyError::Header {
            line: ln,
            what,
            text: l.to_string(),
        };
        let w: Vec<&str> = l.split_whitespace().collect();
        match w.first().copied() {
            None | Some("ply") | Some("comment") | Some("obj_info") => {}
            Some("format") => {
                format = Some(match w.get(1).copied() {
                    Some("ascii") => Format::Ascii,
                    Some("binary_little_endian") => Format::Le,
                    Some("binary_big_endian") => Format::Be,
                    _ => return Err(bad("unknown format")),
                })
            }
            Some("element") => {
                let (Some(name), Some(count)) = (w.get(1), w.get(2).and_then(|c| c.parse().ok()))
                else {
                    return Err(bad("malformed element"));
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
                    .ok_or(PlyError::PropertyBeforeElement(ln))?;
                el.props.push(parse_property(&w, ln, l)?);
            }
            Some(_) => return Err(bad("unknown header line")),
        }
    }
    let format = format.ok_or(PlyError::NoFormat)?;
    check_counts(&elements, format, bytes.len().saturating_sub(body))?;
    Ok(Header {
        format,
        elements,
        body,
        lines: header.lines().count() + 1,
    })
}

/// The reader of the body that follows `h` in `bytes`.
fn body_source<'a>(bytes: &'a [u8], h: &Header) -> Result<Box<dyn Source + 'a>, PlyError> {
    Ok(match h.format {
        Format::Ascii => {
            let text = std::str::from_utf8(&bytes[h.body.min(bytes.len())..])
                .map_err(|_| PlyError::BodyNotText)?;
            Box::new(Ascii {
                lines: text.lines().enumerate().peekable(),
                cur: Vec::new(),
                pos: 0,
                line: 0,
                offset: h.lines,
            })
        }
        f => Box::new(Binary {
            b: bytes,
            i: h.body,
            be: f == Format::Be,
        }),
    })
}

/// Where the properties the mesh uses sit in an element's property list.
struct Layout {
    xyz: [Option<usize>; 3],
    normal: [Option<usize>; 3],
    uv: [Option<usize>; 2],
    color: [Option<usize>; 3],
    indices: Option<usize>,
    texcoord: Option<usize>,
}

impl Layout {
    fn of(el: &Element) -> Layout {
        let find = |n: &[&str]| el.props.iter().position(|p| n.contains(&p.name.as_str()));
        Layout {
            xyz: [find(&["x"]), find(&["y"]), find(&["z"])],
            normal: [find(&["nx"]), find(&["ny"]), find(&["nz"])],
            uv: [
                find(&["s", "u", "texture_u", "texture_s"]),
                find(&["t", "v", "texture_v", "texture_t"]),
            ],
            color: [
                find(&["red", "r", "diffuse_red"]),
                find(&["green", "g", "diffuse_green"]),
                find(&["blue", "b", "diffuse_blue"]),
            ],
            indices: find(&["vertex_indices", "vertex_index"]),
            texcoord: find(&["texcoord"]),
        }
    }
}

/// The mesh's arrays as the elements are read.
#[derive(Default)]
struct MeshArrays {
    positions: Vec<[f64; 3]>,
    normals: Vec<[f64; 3]>,
    uvs: Vec<[f64; 2]>,
    colors: Vec<[f64; 3]>,
    corner_uvs: Vec<[f64; 2]>,
    face_counts: Vec<u32>,
    face_indices: Vec<u32>,
}

impl MeshArrays {
    /// Vertex `k` from its property values `vals`.
    fn vertex(
        &mut self,
        k: usize,
        vals: &[Vec<f64>],
        el: &Element,
        at: &Layout,
    ) -> Result<(), PlyError> {
        // A property declared as a list may hold no value: read the first one, if any.
        let first = |i: usize| vals[i].first().copied();
        let g = |i: Option<usize>| i.and_then(first);
        let (Some(x), Some(y), Some(z)) = (g(at.xyz[0]), g(at.xyz[1]), g(at.xyz[2])) else {
            return Err(PlyError::EmptyCoordinate(k));
        };
        let p = [x, y, z];
        if p.iter().any(|x| !x.is_finite()) {
            return Err(PlyError::NonFinite {
                vertex: k,
                position: p,
            });
        }
        self.positions.push(p);
        if let (Some(a), Some(b), Some(c)) = (g(at.normal[0]), g(at.normal[1]), g(at.normal[2])) {
            self.normals.push([a, b, c]);
        }
        if let (Some(a), Some(b)) = (g(at.uv[0]), g(at.uv[1])) {
            self.uvs.push([a, b]);
        }
        if let [Some(r), Some(gg), Some(b)] = at.color {
            let scale = if el.props[r].ty == Scalar::U8 {
                1.0 / 255.0
            } else {
                1.0
            };
            if let (Some(r), Some(gg), Some(b)) = (first(r), first(gg), first(b)) {
                self.colors.push([r * scale, gg * scale, b * scale]);
            }
        }
        Ok(())
    }

    /// Face `k` from its property values `vals`: whole, distinct, existing vertex indices.
    fn face(&mut self, k: usize, vals: &[Vec<f64>], at: &Layout) -> Result<(), PlyError> {
        let idx = &vals[at.indices.unwrap_or(0)];
        if idx.len() < 3 {
            return Err(PlyError::TooFewCorners {
                face: k,
                corners: idx.len(),
            });
        }
        // Large faces find repeats through a set: a scan per corner was O(k²).
        let mut seen = std::collections::HashSet::new();
        for (c, &i) in idx.iter().enumerate() {
            // `i as usize` would turn NaN into 0 and 1.5 into 1: only whole numbers.
            if !(i >= 0.0 && i.fract() == 0.0 && i < self.positions.len() as f64) {
                return Err(PlyError::BadIndex {
                    face: k,
                    index: i,
                    vertices: self.positions.len(),
                });
            }
            let repeated = if idx.len() > 32 {
                !seen.insert(i as u32)
            } else {
                idx[..c].contains(&i)
            };
            if repeated {
                return Err(PlyError::RepeatedVertex { face: k, vertex: i });
            }
            self.face_indices.push(i as u32);
        }
        self.face_counts.push(idx.len() as u32);
        if let Some(t) = at.texcoord {
            let t = &vals[t];
            if t.len() != 2 * idx.len() {
                return Err(PlyError::Texcoords {
                    face: k,
                    values: t.len(),
                    corners: idx.len(),
                });
            }
            self.corner_uvs
                .extend(t.chunks_exact(2).map(|c| [c[0], c[1]]));
        }
        Ok(())
    }

    /// The mesh, with the attributes every vertex (or corner) has.
    fn finish(self) -> Result<Mesh, PlyError> {
        let nv = self.positions.len();
        let mut mesh = Mesh::new(self.positions, self.face_counts, self.face_indices)
            .map_err(|e| PlyError::Mesh(e.to_string()))?;
        let vertex = |values| Attribute {
            domain: Domain::Vertex,
            values,
        };
        if self.normals.len() == nv && nv > 0 {
            mesh.normals = Some(vertex(self.normals));
        }
        if !self.corner_uvs.is_empty() {
            mesh.uvs = Some(Attribute {
                domain: Domain::Corner,
                values: self.corner_uvs,
            });
        } else if self.uvs.len() == nv && nv > 0 {
            mesh.uvs = Some(Attribute {
                domain: Domain::Vertex,
                values: self.uvs,
            });
        }
        if self.colors.len() == nv && nv > 0 {
            mesh.colors = Some(vertex(self.colors));
        }
        Ok(mesh)
    }
}

/// Reads one element instance's property values into `vals` (one list per property).
fn read_instance(
    src: &mut dyn Source,
    el: &Element,
    k: usize,
    vals: &mut [Vec<f64>],
) -> Result<(), PlyError> {
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
                    return Err(PlyError::ListLength {
                        element: el.name.clone(),
                        index: k,
                        len: n,
                    });
                }
                for _ in 0..n as usize {
                    vals[pi].push(src.scalar(p.ty)?);
                }
            }
        }
    }
    src.end()
}

/// Reads every instance of `el`, adding vertices and faces to `out` (other elements are
/// read and skipped).
fn read_element(src: &mut dyn Source, el: &Element, out: &mut MeshArrays) -> Result<(), PlyError> {
    let at = Layout::of(el);
    let is_vertex = el.name == "vertex";
    let is_face = el.name == "face";
    if is_vertex && at.xyz.iter().any(Option::is_none) {
        return Err(PlyError::NoCoordinates);
    }
    if is_face && at.indices.is_none() {
        return Err(PlyError::NoIndices);
    }
    if el.props.is_empty() && el.count > 0 {
        // Nothing to read per instance: a binary body would be looped over `count` times
        // without consuming a byte.
        return Err(PlyError::NoProperties {
            element: el.name.clone(),
            count: el.count,
        });
    }
    let mut vals: Vec<Vec<f64>> = vec![Vec::new(); el.props.len()];
    for k in 0..el.count {
        read_instance(src, el, k, &mut vals)?;
        if is_vertex {
            out.vertex(k, &vals, el, &at)?;
        } else if is_face {
            out.face(k, &vals, &at)?;
        }
    }
    Ok(())
}

/// Reads a PLY file (ASCII or binary). Errors give the header or body line (ASCII) or the
/// byte offset (binary).
pub fn read_ply(bytes: &[u8]) -> Result<Mesh, PlyError> {
    let header = parse_header(bytes)?;
    let mut src = body_source(bytes, &header)?;
    let mut out = MeshArrays::default();
    for el in &header.elements {
        read_element(src.as_mut(), el, &mut out)?;
    }
    out.finish()
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
