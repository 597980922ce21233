//! Decoding a plugin's response into socket values: JSON literals, and `.npy` arrays that
//! must stay inside the call folder, checked for shape, finiteness and valid indices.

pub use super::decode_error::DecodeError;
use crate::plugin::npy::{DType, NpyArray};
use cgnodes_api::types::*;
use serde_json::{Map, Value as J};
use std::collections::BTreeMap;
use std::path::{Component, Path};
use std::sync::Arc;

/// Reads a plugin's output `j` as a value of type `ty`. Array paths are resolved in `dir`
/// and must stay inside it; `inputs` are the values sent, for `"base"` references.
pub fn decode(
    ty: &SocketType,
    j: &J,
    dir: &Path,
    inputs: &BTreeMap<String, Value>,
) -> Result<Value, DecodeError> {
    let r = Reader { dir, inputs };
    r.value(ty, j)
}

/// The faces of a mesh as sizes and indices (USD's `faceVertexCounts`/`faceVertexIndices`).
type Faces = (Vec<u32>, Vec<u32>);

struct Reader<'a> {
    dir: &'a Path,
    inputs: &'a BTreeMap<String, Value>,
}

impl Reader<'_> {
    /// The array named by `o[key]`, if the key is present; the path must stay in the folder.
    fn array(&self, o: &Map<String, J>, key: &str) -> Result<Option<NpyArray>, DecodeError> {
        let Some(p) = o.get(key) else {
            return Ok(None);
        };
        let p = p.as_str().ok_or_else(|| DecodeError::NotAFileName {
            key: key.into(),
            got: p.to_string(),
        })?;
        let path = Path::new(p);
        let path = if path.is_absolute() {
            if !path.starts_with(self.dir)
                || path.components().any(|c| matches!(c, Component::ParentDir))
            {
                return Err(DecodeError::OutsideFolder {
                    key: key.into(),
                    path: p.into(),
                });
            }
            path.to_path_buf()
        } else {
            if path
                .components()
                .any(|c| !matches!(c, Component::Normal(_) | Component::CurDir))
            {
                return Err(DecodeError::LeavesFolder {
                    key: key.into(),
                    path: p.into(),
                });
            }
            self.dir.join(path)
        };
        NpyArray::read(&path)
            .map(Some)
            .map_err(|source| DecodeError::Array {
                key: key.into(),
                source,
            })
    }

    /// The array named by `o[key]`, which must be present (`what` names the value for the
    /// error).
    fn need(&self, o: &Map<String, J>, key: &str, what: &str) -> Result<NpyArray, DecodeError> {
        self.array(o, key)?.ok_or_else(|| DecodeError::Missing {
            what: what.into(),
            key: key.into(),
        })
    }

    /// One value of type `ty`: a dispatch over the socket types to their readers.
    fn value(&self, ty: &SocketType, j: &J) -> Result<Value, DecodeError> {
        use SocketType as T;
        let obj = || {
            j.as_object().ok_or_else(|| DecodeError::NotAnObject {
                ty: ty.clone(),
                got: brief(j),
            })
        };
        Ok(match ty {
            T::Mesh => Value::Mesh(Arc::new(self.mesh(obj()?)?)),
            T::Image => Value::Image(Arc::new(self.image(obj()?)?)),
            T::Points => Value::Points(Arc::new(self.points(obj()?)?)),
            T::Curve => Value::Curve(Arc::new(self.curve(obj()?)?)),
            T::Table => Value::Table(Arc::new(table(obj()?)?)),
            T::Camera => Value::Camera(Arc::new(from_serde(j, ty)?)),
            T::Light => Value::Light(Arc::new(from_serde(j, ty)?)),
            T::Material => Value::Material(Arc::new(from_serde(j, ty)?)),
            T::Skeleton => Value::Skeleton(Arc::new(from_serde(j, ty)?)),
            T::Model => Value::Model(Arc::new(from_serde(j, ty)?)),
            T::Scene => return Err(DecodeError::Scene),
            T::List(inner) => self.list(inner, j)?,
            plain => Value::from_json(plain, j).map_err(DecodeError::Literal)?,
        })
    }

    /// A list of `inner` values from a JSON array; errors name the item.
    fn list(&self, inner: &SocketType, j: &J) -> Result<Value, DecodeError> {
        let items = j
            .as_array()
            .ok_or_else(|| DecodeError::NotAList(brief(j)))?;
        Ok(Value::List(Arc::new(
            items
                .iter()
                .enumerate()
                .map(|(index, x)| {
                    self.value(inner, x).map_err(|e| DecodeError::Item {
                        index,
                        source: Box::new(e),
                    })
                })
                .collect::<Result<_, _>>()?,
        )))
    }

    /// An image from `pixels`, (H, W, 4) or (H, W, 3) (alpha 1).
    fn image(&self, o: &Map<String, J>) -> Result<Image, DecodeError> {
        let a = self.need(o, "pixels", "image")?;
        let (h, w, c) = match a.shape[..] {
            [h, w, c] if c == 3 || c == 4 => (h, w, c),
            _ => return Err(DecodeError::ImageShape(a.shape_str())),
        };
        let v = a.to_f32();
        let pixels = v
            .chunks_exact(c)
            .map(|p| [p[0], p[1], p[2], if c == 4 { p[3] } else { 1.0 }])
            .collect();
        Ok(Image {
            width: u32::try_from(w).map_err(|_| DecodeError::ImageSize("wide"))?,
            height: u32::try_from(h).map_err(|_| DecodeError::ImageSize("tall"))?,
            pixels,
        })
    }

    /// Points from `positions`, `dim`, and named per-point `scalars` and `vectors`.
    fn points(&self, o: &Map<String, J>) -> Result<Points, DecodeError> {
        let positions = vec3s(&self.need(o, "positions", "points")?, "points 'positions'")?;
        let n = positions.len();
        let dim = match o.get("dim") {
            None => 3,
            Some(d) => match d.as_u64() {
                Some(2) => 2,
                Some(3) => 3,
                _ => return Err(DecodeError::PointsDim(d.clone())),
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
                    return Err(DecodeError::ScalarShape {
                        name: name.clone(),
                        n,
                        shape: a.shape_str(),
                    });
                }
                p.scalars.insert(name.clone(), finite(a.to_f64(), name)?);
            }
        }
        if let Some(s) = o.get("vectors").and_then(J::as_object) {
            for name in s.keys() {
                let v = vec3s(&self.need(s, name, "points 'vectors'")?, name)?;
                if v.len() != n {
                    return Err(DecodeError::VectorRows {
                        name: name.clone(),
                        rows: v.len(),
                        n,
                    });
                }
                p.vectors.insert(name.clone(), v);
            }
        }
        Ok(p)
    }

    /// A polyline from `points` and `closed`.
    fn curve(&self, o: &Map<String, J>) -> Result<Curve, DecodeError> {
        let points = vec3s(&self.need(o, "points", "curve")?, "curve 'points'")?;
        let closed = o.get("closed").and_then(J::as_bool).unwrap_or(false);
        Ok(Curve { points, closed })
    }

    /// A mesh: a `base` input, new positions and faces, then its attributes; checked.
    fn mesh(&self, o: &Map<String, J>) -> Result<Mesh, DecodeError> {
        let base = self.base(o)?;
        let positions = match self.array(o, "positions")? {
            Some(a) => Some(vec3s(&a, "mesh 'positions'")?),
            None => None,
        };
        let faces = self.faces(o)?;
        let mut mesh = match (base, positions, faces) {
            (Some(b), p, f) => {
                let mut m = (*b).clone();
                if let Some(p) = p {
                    if f.is_none() && p.len() != m.positions.len() {
                        return Err(DecodeError::PositionsVsBase {
                            rows: p.len(),
                            vertices: m.positions.len(),
                        });
                    }
                    m.positions = p;
                }
                if let Some((c, i)) = f {
                    m.set_faces(c, i);
                }
                m
            }
            (None, Some(p), Some((c, i))) => Mesh::new(p, c, i)?,
            (None, None, _) => return Err(DecodeError::NoPositions),
            (None, Some(_), None) => return Err(DecodeError::NoFaces),
        };
        self.standard_attributes(o, &mut mesh)?;
        self.custom_attributes(o, &mut mesh)?;
        mesh.check()?;
        Ok(mesh)
    }

    /// The input mesh named by `base`, which the response edits instead of sending it back.
    fn base(&self, o: &Map<String, J>) -> Result<Option<Arc<Mesh>>, DecodeError> {
        let Some(b) = o.get("base") else {
            return Ok(None);
        };
        let name = b
            .as_str()
            .ok_or_else(|| DecodeError::BaseNotName(b.clone()))?;
        match self.inputs.get(name) {
            Some(Value::Mesh(m)) => Ok(Some(m.clone())),
            _ => Err(DecodeError::BaseNotMesh(name.into())),
        }
    }

    /// The faces, from `triangles` (F, 3) or from `face_counts` with `face_indices`.
    fn faces(&self, o: &Map<String, J>) -> Result<Option<Faces>, DecodeError> {
        if let Some(t) = self.array(o, "triangles")? {
            if t.shape.len() != 2 || t.shape[1] != 3 {
                return Err(DecodeError::TriangleShape(t.shape_str()));
            }
            return Ok(Some((vec![3u32; t.shape[0]], indices(&t, "triangles")?)));
        }
        match (
            self.array(o, "face_counts")?,
            self.array(o, "face_indices")?,
        ) {
            (Some(c), Some(i)) => {
                if c.shape.len() != 1 || i.shape.len() != 1 {
                    return Err(DecodeError::FaceArrayShape {
                        counts: c.shape_str(),
                        indices: i.shape_str(),
                    });
                }
                Ok(Some((
                    indices(&c, "face_counts")?,
                    indices(&i, "face_indices")?,
                )))
            }
            (None, None) => Ok(None),
            _ => Err(DecodeError::HalfFaces),
        }
    }

    /// The mesh's `uvs`, `normals` and `colors`, each with its `*_domain`.
    fn standard_attributes(&self, o: &Map<String, J>, mesh: &mut Mesh) -> Result<(), DecodeError> {
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
        Ok(())
    }

    /// The mesh's named `attributes`: float or int (n,), vec2 (n, 2) or vec3 (n, 3).
    fn custom_attributes(&self, o: &Map<String, J>, mesh: &mut Mesh) -> Result<(), DecodeError> {
        let Some(attrs) = o.get("attributes").and_then(J::as_object) else {
            return Ok(());
        };
        for (name, spec) in attrs {
            let spec = spec
                .as_object()
                .ok_or_else(|| DecodeError::AttributeNotObject(name.clone()))?;
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
                    return Err(DecodeError::AttributeShape {
                        name: name.clone(),
                        shape: a.shape_str(),
                    })
                }
            };
            mesh.attributes.insert(name.clone(), data);
        }
        Ok(())
    }
}

/// A table from `columns` ({name: [numbers]}), their `order`, and string `meta`.
fn table(o: &Map<String, J>) -> Result<Table, DecodeError> {
    let cols = o
        .get("columns")
        .and_then(J::as_object)
        .ok_or(DecodeError::NoColumns)?;
    let order: Vec<String> = match o.get("order").and_then(J::as_array) {
        Some(a) => a
            .iter()
            .filter_map(|x| x.as_str().map(String::from))
            .collect(),
        None => cols.keys().cloned().collect(),
    };
    let mut t = Table::default();
    for name in order {
        let col = cols
            .get(&name)
            .and_then(J::as_array)
            .ok_or_else(|| DecodeError::ColumnNotList(name.clone()))?;
        let vals = col
            .iter()
            .map(|x| {
                x.as_f64().ok_or_else(|| DecodeError::ColumnNotNumber {
                    name: name.clone(),
                    got: x.clone(),
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
    Ok(t)
}

fn from_serde<T: serde::de::DeserializeOwned>(j: &J, ty: &SocketType) -> Result<T, DecodeError> {
    serde_json::from_value(j.clone()).map_err(|source| DecodeError::Serde {
        ty: ty.clone(),
        source,
    })
}

fn brief(j: &J) -> String {
    let s = j.to_string();
    if s.chars().count() > 80 {
        format!("{}...", s.chars().take(80).collect::<String>())
    } else {
        s
    }
}

fn finite(v: Vec<f64>, what: &str) -> Result<Vec<f64>, DecodeError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(DecodeError::NotFinite {
            what: what.into(),
            index,
            value: v[index],
        }),
        None => Ok(v),
    }
}

/// Rows of `width` values from an (N, width) array, finite.
fn rows<const W: usize>(a: &NpyArray, what: &str) -> Result<Vec<[f64; W]>, DecodeError> {
    if a.shape.len() != 2 || a.shape[1] != W {
        return Err(DecodeError::RowShape {
            what: what.into(),
            width: W,
            shape: a.shape_str(),
        });
    }
    let v = finite(a.to_f64(), what)?;
    Ok(v.chunks_exact(W)
        .map(|c| std::array::from_fn(|k| c[k]))
        .collect())
}

fn vec3s(a: &NpyArray, what: &str) -> Result<Vec<[f64; 3]>, DecodeError> {
    rows::<3>(a, what)
}

fn vec2s(a: &NpyArray, what: &str) -> Result<Vec<[f64; 2]>, DecodeError> {
    rows::<2>(a, what)
}

fn indices(a: &NpyArray, what: &'static str) -> Result<Vec<u32>, DecodeError> {
    a.to_i64()
        .map_err(|source| DecodeError::Indices { what, source })?
        .into_iter()
        .map(|index| u32::try_from(index).map_err(|_| DecodeError::BadIndex { what, index }))
        .collect()
}

fn parse_domain(s: &J, what: &str) -> Result<Domain, DecodeError> {
    match s.as_str() {
        Some("vertex") | None => Ok(Domain::Vertex),
        Some("corner") => Ok(Domain::Corner),
        Some("face") => Ok(Domain::Face),
        Some(o) => Err(DecodeError::UnknownDomain {
            what: what.into(),
            got: o.into(),
        }),
    }
}
