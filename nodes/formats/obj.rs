//! Wavefront OBJ: reading through tobj (polygons of any arity, per-corner UVs and normals,
//! groups merged or one picked by name) and writing with `vt`/`vn` plus an MTL file and the
//! texture image when the mesh carries a material.

use cgnodes_api::prelude::*;
use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

/// Finds the first line of an OBJ file that is malformed or refers past the data read so far:
/// bad numbers, NaN/infinite coordinates, faces with fewer than 3 corners, repeated or
/// out-of-range indices. Used to put a line number on tobj's and the mesh checker's errors.
pub fn find_bad_obj_line(text: &str) -> Option<(usize, String)> {
    scan_obj(text, true, &mut [true; 2])
}

/// Like `find_bad_obj_line` with the numbers of `v`/`vt`/`vn` lines only counted, not parsed:
/// the check every OBJ gets before tobj reads it (tobj parses the numbers itself, and the
/// mesh checker rejects non-finite ones; parsing them twice made loading 1.7x slower).
/// Also says, from the same pass, whether every face corner names a texture coordinate and
/// whether every one names a normal: tobj fills a missing index with another corner's (or the
/// first `vt`/`vn` of the file), so UVs and normals are kept only when complete (issue 23).
fn find_bad_obj_index(text: &str) -> (Option<(usize, String)>, [bool; 2]) {
    let mut complete = [true; 2];
    let bad = scan_obj(text, false, &mut complete);
    (bad, complete)
}

/// `complete` is and-ed with whether each `f` corner names a texture coordinate and a normal.
fn scan_obj(text: &str, numbers: bool, complete: &mut [bool; 2]) -> Option<(usize, String)> {
    let (mut nv, mut nt, mut nn) = (0i64, 0i64, 0i64);
    let mut seen = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let ln = i + 1;
        let mut w = line.split_whitespace();
        let Some(kw) = w.next() else { continue };
        let nums = |w: std::str::SplitWhitespace, min: usize| -> Result<(), String> {
            if !numbers {
                return Ok(());
            }
            let mut found = 0;
            for s in w {
                let x: f64 = s.parse().map_err(|_| format!("'{s}' is not a number"))?;
                if !x.is_finite() {
                    return Err(format!("'{s}' is not a finite number"));
                }
                found += 1;
            }
            if found < min {
                return Err(format!("expected {min} numbers, found {found}"));
            }
            Ok(())
        };
        let r = match kw {
            "v" => {
                nv += 1;
                nums(w, 3)
            }
            "vt" => {
                nt += 1;
                nums(w, 1)
            }
            "vn" => {
                nn += 1;
                nums(w, 3)
            }
            "f" | "l" => (|| {
                seen.clear();
                for corner in w {
                    let mut parts = corner.split('/');
                    let mut has = [false; 2];
                    for (k, count) in [nv, nt, nn].into_iter().enumerate() {
                        let Some(p) = parts.next() else { break };
                        if p.is_empty() && k > 0 {
                            continue;
                        }
                        if k > 0 {
                            has[k - 1] = true;
                        }
                        let i: i64 = p
                            .parse()
                            .map_err(|_| format!("'{corner}' is not a face corner"))?;
                        let abs = if i < 0 { count + i + 1 } else { i };
                        if i == 0 || abs < 1 || abs > count {
                            let what = ["vertex", "texture coordinate", "normal"][k];
                            return Err(format!(
                                "{what} index {i} is out of range ({count} defined so far)"
                            ));
                        }
                        if k == 0 {
                            seen.push(abs);
                        }
                    }
                    if kw == "f" {
                        complete[0] &= has[0];
                        complete[1] &= has[1];
                    }
                }
                if kw == "l" {
                    return Ok(()); // a polyline: its indices are in range, nothing else to check
                }
                if let Some(abs) = first_repeat(&seen) {
                    return Err(format!("degenerate face: vertex {abs} appears twice"));
                }
                if seen.len() < 3 {
                    return Err(format!(
                        "degenerate face: {} corners, a face needs at least 3",
                        seen.len()
                    ));
                }
                Ok(())
            })(),
            _ => Ok(()),
        };
        if let Err(e) = r {
            return Some((ln, format!("{e}: '{}'", line.trim())));
        }
    }
    None
}

/// The first corner (in order) whose vertex appeared earlier in `face`: a scan for small
/// faces, a set for large ones (a scan per corner was quadratic in the face's size).
fn first_repeat(face: &[i64]) -> Option<i64> {
    if face.len() <= 32 {
        return (1..face.len())
            .find(|&k| face[..k].contains(&face[k]))
            .map(|k| face[k]);
    }
    let mut set = std::collections::HashSet::with_capacity(face.len());
    face.iter().copied().find(|&v| !set.insert(v))
}

/// The first malformed line of the OBJ file at `path`, if it can be read and has one.
fn locate_bad_line(path: &Path) -> Option<(usize, String)> {
    std::fs::read_to_string(path)
        .ok()
        .and_then(|t| find_bad_obj_line(&t))
}

/// The first bad line of the file at `path` if there is one, else `otherwise`.
fn located(path: &Path, otherwise: ObjError) -> ObjError {
    match locate_bad_line(path) {
        Some((line, message)) => ObjError::Line { line, message },
        None => otherwise,
    }
}

/// Why an OBJ file could not be read: the line at fault when one is found.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ObjError {
    /// The file could not be read.
    #[error("{0}")]
    Read(String),
    /// The file is not UTF-8.
    #[error("not UTF-8 text: {0}")]
    NotText(String),
    /// A malformed line or an index past the data read so far.
    #[error("line {line}: {message}")]
    Line {
        /// The 1-based line.
        line: usize,
        /// What is wrong with it.
        message: String,
    },
    /// tobj refused the file and no bad line was found.
    #[error("{0}")]
    Tobj(String),
    /// `group` names no `o`/`g` block.
    #[error("no group or object named '{group}'; the file has: {names}")]
    NoGroup {
        /// The group asked for.
        group: String,
        /// The file's block names, comma-separated.
        names: String,
    },
    /// No face in the selected blocks.
    #[error("no faces: a mesh needs at least one polygon (f lines)")]
    NoFaces,
    /// The faces do not make a valid mesh (`Mesh::new`).
    #[error("{0}")]
    Mesh(String),
    /// One block's faces do not make a valid mesh.
    #[error("object '{object}': {message}")]
    Object {
        /// The `o`/`g` block.
        object: String,
        /// `Mesh::new`'s error.
        message: String,
    },
}

/// The tobj materials of an OBJ file, or why its material library could not be read.
pub type ObjMaterials = Result<Vec<tobj::Material>, tobj::LoadError>;

/// Runs tobj on `path` (polygons kept, separate position/UV/normal indices). The text is
/// checked with `find_bad_obj_index` first, so a bad index is reported with its line and
/// tobj never sees an index it would mishandle (issue 23: a huge negative texture index
/// overflowed its `vt * 2`, and index 0 became "the previous corner's UV"); a later failure
/// is located by `find_bad_obj_line` when it can be. MTL libraries are read through `load_mtl`.
fn read_tobj(path: &Path) -> Result<(Vec<tobj::Model>, ObjMaterials, [bool; 2]), ObjError> {
    let opts = tobj::LoadOptions {
        triangulate: false,
        single_index: false,
        ..Default::default()
    };
    let bytes = std::fs::read(path).map_err(|e| ObjError::Read(e.to_string()))?;
    let text = std::str::from_utf8(&bytes).map_err(|e| ObjError::NotText(e.to_string()))?;
    let (bad, complete) = find_bad_obj_index(text);
    if let Some((line, message)) = bad {
        return Err(ObjError::Line { line, message });
    }
    let dir = path.parent().unwrap_or(Path::new(""));
    let (models, mats) =
        tobj::load_obj_buf(&mut text.as_bytes(), &opts, |mtl| load_mtl(&dir.join(mtl))).map_err(
            |e| match find_bad_obj_line(text) {
                Some((line, message)) => ObjError::Line { line, message },
                None => ObjError::Tobj(e.to_string()),
            },
        )?;
    Ok((models, mats, complete))
}

/// Reads an MTL library for tobj after `complete_mtl_colours`.
fn load_mtl(path: &Path) -> tobj::MTLLoadResult {
    let bytes = std::fs::read(path).map_err(|_| tobj::LoadError::OpenFileFailed)?;
    let text = complete_mtl_colours(&String::from_utf8_lossy(&bytes));
    tobj::load_mtl_buf(&mut text.as_bytes())
}

/// MTL text with every colour statement (`Ka`, `Kd`, `Ks`, `Ke`) given three numbers: the
/// Wavefront MTL specification lets `Kd r` stand for `Kd r r r` ("g and b are optional"),
/// and a statement with no or two numbers becomes one tobj rejects as a parse error
/// (tobj 4.0 panics on fewer than three numbers; found by the `mtl` fuzz target).
pub fn complete_mtl_colours(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 16);
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some(key @ ("Ka" | "Kd" | "Ks" | "Ke")) => {
                let vals: Vec<&str> = words.collect();
                match vals.len() {
                    1 => out.push_str(&format!("{key} {0} {0} {0}", vals[0])),
                    0 | 2 => out.push_str(&format!("{key} ? ? ?")),
                    _ => out.push_str(line),
                }
            }
            _ => out.push_str(line),
        }
        out.push('\n');
    }
    out
}

/// Corner counts of a tobj mesh's faces (all 3 when tobj gives no arities).
fn face_counts(mesh: &tobj::Mesh) -> Vec<u32> {
    if mesh.face_arities.is_empty() {
        vec![3u32; mesh.indices.len() / 3]
    } else {
        mesh.face_arities.clone()
    }
}

/// Per-corner UVs of a tobj mesh, when every corner has one.
fn corner_uvs(mesh: &tobj::Mesh) -> Option<Vec<[f64; 2]>> {
    (mesh.texcoord_indices.len() == mesh.indices.len() && !mesh.texcoords.is_empty()).then(|| {
        mesh.texcoord_indices
            .iter()
            .map(|&t| {
                [
                    mesh.texcoords[2 * t as usize],
                    mesh.texcoords[2 * t as usize + 1],
                ]
            })
            .collect()
    })
}

/// Per-corner normals of a tobj mesh, when every corner has one.
fn corner_normals(mesh: &tobj::Mesh) -> Option<Vec<[f64; 3]>> {
    (mesh.normal_indices.len() == mesh.indices.len() && !mesh.normals.is_empty()).then(|| {
        mesh.normal_indices
            .iter()
            .map(|&t| {
                let t = 3 * t as usize;
                [mesh.normals[t], mesh.normals[t + 1], mesh.normals[t + 2]]
            })
            .collect()
    })
}

/// One `o`/`g` block of an OBJ file with faces, as its own mesh.
#[derive(Clone, Debug)]
pub struct ObjObject {
    /// The block's name.
    pub name: String,
    /// Its vertices (numbered per block by tobj), polygon faces, and per-corner UVs and
    /// normals when every corner has them.
    pub mesh: Mesh,
    /// Index into the file's materials (`usemtl`), if any.
    pub material_id: Option<usize>,
}

/// Reads an OBJ file with tobj into one mesh per `o`/`g` block that has faces (blocks are not
/// merged or welded), plus the materials of its MTL libraries, for scene loaders that keep
/// objects and materials apart. Errors name the first bad line when there is one, like
/// `load_obj`; a block whose mesh is invalid otherwise gives `object '<name>': <error>`.
pub fn load_obj_objects(path: &Path) -> Result<(Vec<ObjObject>, ObjMaterials), ObjError> {
    let (models, materials, [all_uv, all_n]) = read_tobj(path)?;
    let mut objects = Vec::new();
    for m in models {
        let mesh = &m.mesh;
        if mesh.indices.is_empty() {
            continue;
        }
        let positions: Vec<[f64; 3]> = mesh
            .positions
            .chunks_exact(3)
            .map(|p| [p[0], p[1], p[2]])
            .collect();
        let mut out =
            Mesh::new(positions, face_counts(mesh), mesh.indices.clone()).map_err(|e| {
                located(
                    path,
                    ObjError::Object {
                        object: m.name.clone(),
                        message: e.to_string(),
                    },
                )
            })?;
        out.uvs = corner_uvs(mesh).filter(|_| all_uv).map(|values| Attribute {
            domain: Domain::Corner,
            values,
        });
        out.normals = corner_normals(mesh)
            .filter(|_| all_n)
            .map(|values| Attribute {
                domain: Domain::Corner,
                values,
            });
        objects.push(ObjObject {
            name: m.name.clone(),
            mesh: out,
            material_id: mesh.material_id,
        });
    }
    Ok((objects, materials))
}

/// Reads an OBJ file with tobj: positions, polygon faces, and UVs and normals per corner.
/// `group` picks one `o`/`g` block by name; empty merges them all. tobj renumbers vertices
/// per block, so when merging, vertices of different blocks at bit-identical positions are
/// welded back together (OBJ blocks share one vertex list).
pub fn load_obj(path: &Path, group: &str) -> Result<Mesh, ObjError> {
    let (models, _, [all_uv, all_n]) = read_tobj(path)?;
    let models: Vec<&tobj::Model> = if group.is_empty() {
        models.iter().collect()
    } else {
        let sel: Vec<_> = models.iter().filter(|m| m.name == group).collect();
        if sel.is_empty() {
            let names: Vec<&str> = models.iter().map(|m| m.name.as_str()).collect();
            return Err(ObjError::NoGroup {
                group: group.to_string(),
                names: names.join(", "),
            });
        }
        sel
    };
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut weld: HashMap<[u64; 3], u32> = HashMap::new();
    let mut counts = Vec::new();
    let mut idx = Vec::new();
    let mut uvs = Vec::new();
    let mut normals = Vec::new();
    let (mut has_uv, mut has_n) = (all_uv, all_n);
    let multi = models.len() > 1;
    for m in &models {
        let mesh = &m.mesh;
        let mut map = Vec::with_capacity(mesh.positions.len() / 3);
        for p in mesh.positions.chunks_exact(3) {
            let p = [p[0], p[1], p[2]];
            let id = if multi {
                let key = p.map(f64::to_bits);
                *weld.entry(key).or_insert_with(|| {
                    positions.push(p);
                    positions.len() as u32 - 1
                })
            } else {
                positions.push(p);
                positions.len() as u32 - 1
            };
            map.push(id);
        }
        counts.extend(face_counts(mesh));
        idx.extend(mesh.indices.iter().map(|&i| map[i as usize]));
        match corner_uvs(mesh) {
            Some(v) => uvs.extend(v),
            None => has_uv = false,
        }
        match corner_normals(mesh) {
            Some(v) => normals.extend(v),
            None => has_n = false,
        }
    }
    if counts.is_empty() {
        // tobj drops vertices that no face uses, so an empty mesh would hide the file's points
        return Err(located(path, ObjError::NoFaces));
    }
    let mut mesh = Mesh::new(positions, counts, idx)
        .map_err(|e| located(path, ObjError::Mesh(e.to_string())))?;
    if has_uv && !uvs.is_empty() {
        mesh.uvs = Some(Attribute {
            domain: Domain::Corner,
            values: uvs,
        });
    }
    if has_n && !normals.is_empty() {
        mesh.normals = Some(Attribute {
            domain: Domain::Corner,
            values: normals,
        });
    }
    Ok(mesh)
}

/// Writes OBJ text: `v`, `vt` and `vn` (per vertex or per corner), and `f` lines with
/// `v/vt/vn` corners. `mtl` names an MTL file and material to reference (`mtllib`/`usemtl`).
/// Floats use Rust's shortest round-trip formatting, so reading back gives the same values.
pub fn write_obj(mesh: &Mesh, mtl: Option<(&str, &str)>, w: &mut dyn Write) -> std::io::Result<()> {
    writeln!(w, "# written by cgnodes")?;
    if let Some((file, _)) = mtl {
        writeln!(w, "mtllib {file}")?;
    }
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
    }
    let uv = mesh.uvs.as_ref().filter(|u| u.domain != Domain::Face);
    if let Some(uv) = uv {
        for t in &uv.values {
            writeln!(w, "vt {} {}", t[0], t[1])?;
        }
    }
    let nm = mesh.normals.as_ref();
    if let Some(n) = nm {
        for t in &n.values {
            writeln!(w, "vn {} {} {}", t[0], t[1], t[2])?;
        }
    }
    if let Some((_, name)) = mtl {
        writeln!(w, "usemtl {name}")?;
    }
    let index = |d: Domain, v: usize, c: usize, f: usize| match d {
        Domain::Vertex => v + 1,
        Domain::Corner => c + 1,
        Domain::Face => f + 1,
    };
    let mut c = 0usize;
    for (f, face) in mesh.faces().enumerate() {
        write!(w, "f")?;
        for &v in face {
            let v = v as usize;
            write!(w, " {}", v + 1)?;
            match (uv, nm) {
                (Some(t), Some(n)) => write!(
                    w,
                    "/{}/{}",
                    index(t.domain, v, c, f),
                    index(n.domain, v, c, f)
                )?,
                (Some(t), None) => write!(w, "/{}", index(t.domain, v, c, f))?,
                (None, Some(n)) => write!(w, "//{}", index(n.domain, v, c, f))?,
                (None, None) => {}
            }
            c += 1;
        }
        writeln!(w)?;
    }
    Ok(())
}

/// Writes an MTL file for `mat` (`Kd`, `Ke`, `Ns` from roughness, `map_Kd` when a texture
/// file name is given).
pub fn write_mtl(mat: &Material, texture: Option<&str>, w: &mut dyn Write) -> std::io::Result<()> {
    writeln!(w, "# written by cgnodes")?;
    writeln!(w, "newmtl {}", mtl_name(mat))?;
    let c = mat.base_color;
    writeln!(w, "Kd {} {} {}", c[0], c[1], c[2])?;
    writeln!(w, "Ka 0 0 0")?;
    let e = mat.emission;
    if e != [0.0; 3] {
        writeln!(w, "Ke {} {} {}", e[0], e[1], e[2])?;
    }
    // Phong exponent from roughness (Walter et al. 2007: alpha_p = 2 / alpha^2 - 2).
    let a = mat.roughness.clamp(0.01, 1.0);
    writeln!(w, "Ns {}", (2.0 / (a * a) - 2.0).max(0.0))?;
    writeln!(w, "illum 2")?;
    if let Some(t) = texture {
        writeln!(w, "map_Kd {t}")?;
    }
    Ok(())
}

/// The material's name as an MTL identifier.
pub fn mtl_name(mat: &Material) -> String {
    let n: String = mat
        .name
        .chars()
        .map(|c| if c.is_whitespace() { '_' } else { c })
        .collect();
    if n.is_empty() {
        "material".into()
    } else {
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locates_bad_lines() {
        let t = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n";
        let (ln, msg) = find_bad_obj_line(t).unwrap();
        assert_eq!(ln, 4);
        assert!(msg.contains("out of range"), "{msg}");
        assert_eq!(find_bad_obj_line("v 0 0 nan\n").unwrap().0, 1);
        assert_eq!(find_bad_obj_line("v 0 0 0\nv 1 x 0\n").unwrap().0, 2);
        let t = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -1\nf 1 2 2\n";
        let (ln, msg) = find_bad_obj_line(t).unwrap();
        assert_eq!(ln, 5);
        assert!(msg.contains("degenerate"), "{msg}");
    }

    #[test]
    fn objects_keep_their_materials() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/cornell/cornell_box.obj");
        let (objects, mats) = load_obj_objects(&p).unwrap();
        let mats = mats.unwrap();
        assert!(!objects.is_empty() && !mats.is_empty());
        for o in &objects {
            assert!(o.mesh.num_faces() > 0, "{}", o.name);
            assert!(o.material_id.is_some_and(|i| i < mats.len()), "{}", o.name);
        }
        assert!(load_obj_objects(Path::new("/nonexistent/x.obj")).is_err());
    }

    #[test]
    fn a_file_without_faces_is_an_error_not_an_empty_mesh() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("points.obj");
        for text in ["v 0 0 0\nv 1 0 0\n", ""] {
            std::fs::write(&p, text).unwrap();
            let e = load_obj(&p, "").unwrap_err().to_string();
            assert!(e.contains("no faces"), "{e}");
        }
    }

    /// The fuzzer's crash (tobj panicked on `Ks 0.95`): a one-number colour means grey, a
    /// two-number one is an error in the materials, and neither panics.
    #[test]
    fn short_mtl_colours_do_not_panic() {
        let d = tempfile::tempdir().unwrap();
        let obj = d.path().join("m.obj");
        std::fs::write(
            &obj,
            "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
        )
        .unwrap();
        std::fs::write(d.path().join("m.mtl"), "newmtl a\nKs 0.95\nKd\t0.5\n").unwrap();
        let (objects, mats) = load_obj_objects(&obj).unwrap();
        assert_eq!(objects.len(), 1);
        let mats = mats.unwrap();
        assert_eq!(mats[0].specular, Some([0.95; 3]));
        assert_eq!(mats[0].diffuse, Some([0.5; 3]));
        for bad in ["newmtl a\nKs 0.95 0.5\n", "newmtl a\nKa\n"] {
            std::fs::write(d.path().join("m.mtl"), bad).unwrap();
            let (objects, mats) = load_obj_objects(&obj).unwrap();
            assert_eq!(objects.len(), 1, "{bad:?}");
            assert!(mats.is_err(), "{bad:?}");
        }
    }

    /// Writes `files` (name, text) into a fresh folder.
    fn folder(files: &[(&str, &str)]) -> tempfile::TempDir {
        let d = tempfile::tempdir().unwrap();
        for (name, text) in files {
            std::fs::write(d.path().join(name), text).unwrap();
        }
        d
    }

    /// Issue 23: indices tobj would mishandle are refused, with the line, before tobj runs: a
    /// huge negative texture index overflowed tobj's `vt * 2` (a panic with overflow checks),
    /// and texture index 0 silently became "the previous corner's UV".
    #[test]
    fn indices_tobj_mishandles_are_refused_first() {
        for (corner, what) in [
            (
                "1/-9223372036854775807",
                "texture coordinate index -9223372036854775807",
            ),
            ("1/0", "texture coordinate index 0"),
            (
                "1//-9223372036854775807",
                "normal index -9223372036854775807",
            ),
            ("-9223372036854775807", "vertex index -9223372036854775807"),
        ] {
            let obj =
                format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf {corner} 2/1/1 3/1/1\n");
            let d = folder(&[("t.obj", &obj)]);
            let p = d.path().join("t.obj");
            let e = load_obj(&p, "").unwrap_err().to_string();
            assert!(
                e.starts_with("line 6: ") && e.contains(what),
                "{corner}: {e}"
            );
            let e = load_obj_objects(&p).unwrap_err().to_string();
            assert!(e.starts_with("line 6: "), "{e}");
        }
        // Polylines are checked too.
        let d = folder(&[("t.obj", "v 0 0 0\nvt 0 0\nl 1/-9223372036854775807 1/1\n")]);
        let e = load_obj(&d.path().join("t.obj"), "")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("line 3: "), "{e}");
    }

    /// A face with many corners is checked for repeats in linear time (a scan per corner was
    /// quadratic), and the repeat is still found.
    #[test]
    fn repeats_in_large_faces_are_found() {
        let n = 2000;
        let mut t: String = (0..n).map(|k| format!("v {k} {} 0\n", k * k)).collect();
        let mut idx: Vec<String> = (1..=n).map(|k| k.to_string()).collect();
        assert!(find_bad_obj_line(&format!("{t}f {}\n", idx.join(" "))).is_none());
        idx[n - 1] = "5".into();
        t.push_str(&format!("f {}\n", idx.join(" ")));
        let (ln, msg) = find_bad_obj_line(&t).unwrap();
        assert_eq!(ln, n + 1);
        assert!(
            msg.starts_with("degenerate face: vertex 5 appears twice"),
            "{msg}"
        );
    }

    /// Issue 23: corners without a `vt` (or `vn`) got another corner's from tobj; such a
    /// file now loads without UVs (normals) instead of with invented ones.
    #[test]
    fn incomplete_corner_uvs_and_normals_are_dropped() {
        let head = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.25 0.75\nvt 1 0\nvn 0 0 1\n";
        for (faces, uv, n) in [
            ("f 1 2 3\n", false, false),
            ("f 1/1/1 2/2/1 3/2\n", true, false),
            ("f 1/1/1 2//1 3/2/1\n", false, true),
            ("f 1/1/1 2/2/1 3/2/1\n", true, true),
        ] {
            let d = folder(&[("t.obj", &format!("{head}{faces}"))]);
            let p = d.path().join("t.obj");
            let m = load_obj(&p, "").unwrap();
            assert_eq!((m.uvs.is_some(), m.normals.is_some()), (uv, n), "{faces}");
            let (o, _) = load_obj_objects(&p).unwrap();
            let m = &o[0].mesh;
            assert_eq!((m.uvs.is_some(), m.normals.is_some()), (uv, n), "{faces}");
        }
    }
}
