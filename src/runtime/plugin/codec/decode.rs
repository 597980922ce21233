//! Decoding a plugin's response into socket values: JSON literals, and `.npy` arrays that
//! must stay inside the call folder, checked for shape, finiteness and valid indices.

use crate::plugin::npy::{DType, NpyArray};
use cgnodes_api::types::*;
use serde_json::{Map, Value as J};
use std::path::{Component, Path};
use std::sync::Arc;

/// Reads a plugin's output `j` as a value of type `ty`. Array paths are resolved in `dir`
/// and must stay inside it; `inputs` are the values sent, for `"base"` references.
pub fn decode(
    ty: &SocketType,
    j: &J,
    dir: &Path,
    inputs: &std::collections::BTreeMap<String, Value>,
) -> Result<Value, String> {
    let r = Reader { dir, inputs };
    r.value(ty, j)
}

struct Reader<'a> {
    dir: &'a Path,
    inputs: &'a std::collections::BTreeMap<String, Value>,
}

impl Reader<'_> {
    fn array(&self, o: &Map<String, J>, key: &str) -> Result<Option<NpyArray>, String> {
        let Some(p) = o.get(key) else {
            return Ok(None);
        };
        let p = p
            .as_str()
            .ok_or_else(|| format!("'{key}' should name an .npy file, got {p}"))?;
        let path = Path::new(p);
        let path = if path.is_absolute() {
            if !path.starts_with(self.dir)
                || path.components().any(|c| matches!(c, Component::ParentDir))
            {
                return Err(format!(
                    "'{key}': {p} is outside the call folder; write arrays into the folder the request names"
                ));
            }
            path.to_path_buf()
        } else {
            if path
                .components()
                .any(|c| !matches!(c, Component::Normal(_) | Component::CurDir))
            {
                return Err(format!("'{key}': {p} leaves the call folder"));
            }
            self.dir.join(path)
        };
        NpyArray::read(&path)
            .map(Some)
            .map_err(|e| format!("'{key}': {e}"))
    }

    fn need(&self, o: &Map<String, J>, key: &str, what: &str) -> Result<NpyArray, String> {
        self.array(o, key)?
            .ok_or_else(|| format!("{what} has no '{key}'"))
    }

    fn value(&self, ty: &SocketType, j: &J) -> Result<Value, String> {
        use SocketType as T;
        let obj = || {
            j.as_object()
                .ok_or_else(|| format!("expected a {ty} object, got {}", brief(j)))
        };
        Ok(match ty {
            T::Mesh => Value::Mesh(Arc::new(self.mesh(obj()?)?)),
            T::Image => {
                let o = obj()?;
                let a = self.need(o, "pixels", "image")?;
                let (h, w, c) = match a.shape[..] {
                    [h, w, c] if c == 3 || c == 4 => (h, w, c),
                    _ => {
                        return Err(format!(
                            "image 'pixels' should have shape (H, W, 4) or (H, W, 3), got {}",
                            a.shape_str()
                        ))
                    }
                };
                let v = a.to_f32();
                let pixels = v
                    .chunks_exact(c)
                    .map(|p| [p[0], p[1], p[2], if c == 4 { p[3] } else { 1.0 }])
                    .collect();
                Value::Image(Arc::new(Image {
                    width: u32::try_from(w).map_err(|_| "image too wide")?,
                    height: u32::try_from(h).map_err(|_| "image too tall")?,
                    pixels,
                }))
            }
            T::Points => {
                let o = obj()?;
                let positions = vec3s(&self.need(o, "positions", "points")?, "points 'positions'")?;
                let n = positions.len();
                let dim = match o.get("dim") {
                    None => 3,
                    Some(d) => match d.as_u64() {
                        Some(2) => 2,
                        Some(3) => 3,
                        _ => return Err(format!("points 'dim' should be 2 or 3, got {d}")),
                    },
                };
                let mut p = Points {
                    dim,
                    positions,
                    ..Default::default()
                };
                if let Some(s) = o.get("scalars").and_then(J::as_object) {
                    for name in s.keys() {
                        let a = self.need(s, name, "points 'scalars'")?;
                        if a.shape != [n] {
                            return Err(format!(
                                "points scalar '{name}' should have shape ({n},), got {}",
                                a.shape_str()
                            ));
                        }
                        p.scalars.insert(name.clone(), finite(a.to_f64(), name)?);
                    }
                }
                if let Some(s) = o.get("vectors").and_then(J::as_object) {
                    for name in s.keys() {
                        let v = vec3s(&self.need(s, name, "points 'vectors'")?, name)?;
                        if v.len() != n {
                            return Err(format!(
                                "points vector '{name}' has {} rows but there are {n} points",
                                v.len()
                            ));
                        }
                        p.vectors.insert(name.clone(), v);
                    }
                }
                Value::Points(Arc::new(p))
            }
            T::Curve => {
                let o = obj()?;
                let points = vec3s(&self.need(o, "points", "curve")?, "curve 'points'")?;
                let closed = o.get("closed").and_then(J::as_bool).unwrap_or(false);
                Value::Curve(Arc::new(Curve { points, closed }))
            }
            T::Table => {
                let o = obj()?;
                let cols = o
                    .get("columns")
                    .and_then(J::as_object)
                    .ok_or("a table needs 'columns': {name: [numbers]}")?;
                let order: Vec<String> = match o.get("order").and_then(J::as_array) {
                    Some(a) => a
                        .iter()
                        .filter_map(|x| x.as_str().map(String::from))
                        .collect(),
                    None => cols.keys().cloned().collect(),
                };
                let mut t = Table::default();
                for name in order {
                    let col = cols.get(&name).and_then(J::as_array).ok_or_else(|| {
                        format!("table column '{name}' should be a list of numbers")
                    })?;
                    let vals = col
                        .iter()
                        .map(|x| {
                            x.as_f64().ok_or_else(|| {
                                format!("table column '{name}': {x} is not a number")
                            })
                        })
                        .collect::<Result<Vec<_>, _>>()?;
                    t.columns.push((name, vals));
                }
                if let Some(m) = o.get("meta").and_then(J::as_object) {
                    for (k, v) in m {
                        let s = v
                            .as_str()
                            .map(String::from)
                            .unwrap_or_else(|| v.to_string());
                        t.meta.insert(k.clone(), s);
                    }
                }
                Value::Table(Arc::new(t))
            }
            T::Camera => Value::Camera(Arc::new(from_serde(j, ty)?)),
            T::Light => Value::Light(Arc::new(from_serde(j, ty)?)),
            T::Material => Value::Material(Arc::new(from_serde(j, ty)?)),
            T::Skeleton => Value::Skeleton(Arc::new(from_serde(j, ty)?)),
            T::Model => Value::Model(Arc::new(from_serde(j, ty)?)),
            T::Scene => return Err("plugins cannot return scenes".into()),
            T::List(inner) => {
                let items = j
                    .as_array()
                    .ok_or_else(|| format!("expected a list, got {}", brief(j)))?;
                Value::List(Arc::new(
                    items
                        .iter()
                        .enumerate()
                        .map(|(i, x)| self.value(inner, x).map_err(|e| format!("item {i}: {e}")))
                        .collect::<Result<_, _>>()?,
                ))
            }
            plain => Value::from_json(plain, j)?,
        })
    }

    fn mesh(&self, o: &Map<String, J>) -> Result<Mesh, String> {
        let base = match o.get("base") {
            None => None,
            Some(b) => {
                let name = b
                    .as_str()
                    .ok_or_else(|| format!("mesh 'base' should name an input socket, got {b}"))?;
                match self.inputs.get(name) {
                    Some(Value::Mesh(m)) => Some(m.clone()),
                    _ => {
                        return Err(format!(
                            "mesh 'base' names '{name}', which is not a mesh input"
                        ))
                    }
                }
            }
        };
        let positions = match self.array(o, "positions")? {
            Some(a) => Some(vec3s(&a, "mesh 'positions'")?),
            None => None,
        };
        let faces = if let Some(t) = self.array(o, "triangles")? {
            if t.shape.len() != 2 || t.shape[1] != 3 {
                return Err(format!(
                    "mesh 'triangles' should have shape (F, 3), got {}",
                    t.shape_str()
                ));
            }
            Some((vec![3u32; t.shape[0]], indices(&t, "triangles")?))
        } else {
            match (
                self.array(o, "face_counts")?,
                self.array(o, "face_indices")?,
            ) {
                (Some(c), Some(i)) => {
                    if c.shape.len() != 1 || i.shape.len() != 1 {
                        return Err(format!(
                            "mesh 'face_counts' and 'face_indices' should be 1-D, got {} and {}",
                            c.shape_str(),
                            i.shape_str()
                        ));
                    }
                    Some((indices(&c, "face_counts")?, indices(&i, "face_indices")?))
                }
                (None, None) => None,
                _ => return Err("mesh needs both 'face_counts' and 'face_indices'".into()),
            }
        };
        let mut mesh = match (base, positions, faces) {
            (Some(b), p, f) => {
                let mut m = (*b).clone();
                if let Some(p) = p {
                    if f.is_none() && p.len() != m.positions.len() {
                        return Err(format!(
                            "mesh 'positions' has {} rows but its base mesh has {} vertices (send new faces too)",
                            p.len(),
                            m.positions.len()
                        ));
                    }
                    m.positions = p;
                }
                if let Some((c, i)) = f {
                    m.set_faces(c, i);
                }
                m
            }
            (None, Some(p), Some((c, i))) => {
                Mesh::new(p, c, i).map_err(|e| format!("mesh: {e}"))?
            }
            (None, None, _) => return Err("mesh has no 'positions' (and no 'base')".into()),
            (None, Some(_), None) => {
                return Err("mesh has no faces: give 'triangles' or 'face_counts' and 'face_indices' (or a 'base')".into())
            }
        };
        if let Some(a) = self.array(o, "uvs")? {
            let d = parse_domain(o.get("uv_domain").unwrap_or(&J::Null), "uv_domain")?;
            mesh.uvs = Some(Attribute {
                domain: d,
                values: vec2s(&a, "mesh 'uvs'")?,
            });
        }
        if let Some(a) = self.array(o, "normals")? {
            let d = parse_domain(o.get("normal_domain").unwrap_or(&J::Null), "normal_domain")?;
            mesh.normals = Some(Attribute {
                domain: d,
                values: vec3s(&a, "mesh 'normals'")?,
            });
        }
        if let Some(a) = self.array(o, "colors")? {
            let d = parse_domain(o.get("color_domain").unwrap_or(&J::Null), "color_domain")?;
            mesh.colors = Some(Attribute {
                domain: d,
                values: vec3s(&a, "mesh 'colors'")?,
            });
        }
        if let Some(attrs) = o.get("attributes").and_then(J::as_object) {
            for (name, spec) in attrs {
                let spec = spec.as_object().ok_or_else(|| {
                    format!("attribute '{name}' should be {{\"domain\", \"data\"}}")
                })?;
                let d = parse_domain(spec.get("domain").unwrap_or(&J::Null), name)?;
                let a = self.need(spec, "data", &format!("attribute '{name}'"))?;
                let data = match (a.shape.len(), a.shape.get(1)) {
                    (1, _) if matches!(a.dtype, DType::F32 | DType::F64) => {
                        AttributeData::Float(Attribute {
                            domain: d,
                            values: finite(a.to_f64(), name)?,
                        })
                    }
                    (1, _) => AttributeData::Int(Attribute {
                        domain: d,
                        values: a.to_i64()?,
                    }),
                    (2, Some(2)) => AttributeData::Vec2(Attribute {
                        domain: d,
                        values: vec2s(&a, name)?,
                    }),
                    (2, Some(3)) => AttributeData::Vec3(Attribute {
                        domain: d,
                        values: vec3s(&a, name)?,
                    }),
                    _ => {
                        return Err(format!(
                            "attribute '{name}' should have shape (n,), (n, 2) or (n, 3), got {}",
                            a.shape_str()
                        ))
                    }
                };
                mesh.attributes.insert(name.clone(), data);
            }
        }
        mesh.check().map_err(|e| format!("mesh: {e}"))?;
        Ok(mesh)
    }
}

fn from_serde<T: serde::de::DeserializeOwned>(j: &J, ty: &SocketType) -> Result<T, String> {
    serde_json::from_value(j.clone()).map_err(|e| format!("not a valid {ty}: {e}"))
}

fn brief(j: &J) -> String {
    let s = j.to_string();
    if s.chars().count() > 80 {
        format!("{}...", s.chars().take(80).collect::<String>())
    } else {
        s
    }
}

fn finite(v: Vec<f64>, what: &str) -> Result<Vec<f64>, String> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(format!("{what}: element {i} is {}", v[i])),
        None => Ok(v),
    }
}

fn vec3s(a: &NpyArray, what: &str) -> Result<Vec<[f64; 3]>, String> {
    if a.shape.len() != 2 || a.shape[1] != 3 {
        return Err(format!(
            "{what} should have shape (N, 3), got {}",
            a.shape_str()
        ));
    }
    let v = finite(a.to_f64(), what)?;
    Ok(v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
}

fn vec2s(a: &NpyArray, what: &str) -> Result<Vec<[f64; 2]>, String> {
    if a.shape.len() != 2 || a.shape[1] != 2 {
        return Err(format!(
            "{what} should have shape (N, 2), got {}",
            a.shape_str()
        ));
    }
    let v = finite(a.to_f64(), what)?;
    Ok(v.chunks_exact(2).map(|c| [c[0], c[1]]).collect())
}

fn indices(a: &NpyArray, what: &str) -> Result<Vec<u32>, String> {
    a.to_i64()
        .map_err(|e| format!("mesh '{what}': {e}"))?
        .into_iter()
        .map(|i| u32::try_from(i).map_err(|_| format!("mesh '{what}': {i} is not a valid index")))
        .collect()
}

fn parse_domain(s: &J, what: &str) -> Result<Domain, String> {
    match s.as_str() {
        Some("vertex") | None => Ok(Domain::Vertex),
        Some("corner") => Ok(Domain::Corner),
        Some("face") => Ok(Domain::Face),
        Some(o) => Err(format!(
            "{what}: unknown domain '{o}' (vertex, corner or face)"
        )),
    }
}
