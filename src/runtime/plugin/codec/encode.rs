//! Encoding socket values for a plugin request: arrays into `.npy` files in the call
//! folder, named from the socket, and the JSON that points at them.

use crate::plugin::npy::{NpyArray, NpyError};
use cgnodes_api::types::*;
use serde_json::{json, Map, Value as J};
use std::path::Path;

/// Why a value could not be sent to a plugin.
#[derive(Debug, thiserror::Error)]
pub enum EncodeError {
    /// An array file could not be written.
    #[error(transparent)]
    Npy(#[from] NpyError),
    /// A structured value did not serialize.
    #[error("{0}")]
    Serde(#[from] serde_json::Error),
    /// A scene input: scenes do not cross the plugin boundary.
    #[error("scenes cannot be sent to plugins")]
    Scene,
    /// A plain value without a JSON literal.
    #[error("no JSON form for {0}")]
    NoJson(SocketType),
}

/// Writes the arrays of `v` into `dir` (file names starting with `stem`) and returns its JSON
/// form. Array paths in the JSON are absolute.
pub fn encode(v: &Value, dir: &Path, stem: &str) -> Result<J, EncodeError> {
    let mut w = Writer { dir, stem };
    w.value(v, "")
}

struct Writer<'a> {
    dir: &'a Path,
    stem: &'a str,
}

impl Writer<'_> {
    fn array(&mut self, suffix: &str, a: &NpyArray) -> Result<J, EncodeError> {
        let p = self.dir.join(format!("{}{suffix}.npy", self.stem));
        a.write(&p)?;
        Ok(J::String(p.to_string_lossy().into_owned()))
    }

    fn vec3s(&mut self, suffix: &str, v: &[[f64; 3]]) -> Result<J, EncodeError> {
        let flat: Vec<f64> = v.iter().flatten().copied().collect();
        self.array(suffix, &NpyArray::from_f64(&[v.len(), 3], &flat))
    }

    fn value(&mut self, v: &Value, sub: &str) -> Result<J, EncodeError> {
        Ok(match v {
            Value::Mesh(m) => self.mesh(m, sub)?,
            Value::Image(img) => {
                let flat: Vec<f32> = img.pixels.iter().flatten().copied().collect();
                let a = NpyArray::from_f32(&[img.height as usize, img.width as usize, 4], &flat);
                json!({"type": "image", "pixels": self.array(&format!("{sub}.pixels"), &a)?})
            }
            Value::Points(p) => {
                let mut scalars = Map::new();
                for (name, vals) in &p.scalars {
                    let a = NpyArray::from_f64(&[vals.len()], vals);
                    scalars.insert(
                        name.clone(),
                        self.array(&format!("{sub}.s_{}", safe(name)), &a)?,
                    );
                }
                let mut vectors = Map::new();
                for (name, vals) in &p.vectors {
                    vectors.insert(
                        name.clone(),
                        self.vec3s(&format!("{sub}.v_{}", safe(name)), vals)?,
                    );
                }
                json!({"type": "points", "dim": p.dim,
                       "positions": self.vec3s(&format!("{sub}.positions"), &p.positions)?,
                       "scalars": scalars, "vectors": vectors})
            }
            Value::Curve(c) => json!({"type": "curve", "closed": c.closed,
                "points": self.vec3s(&format!("{sub}.points"), &c.points)?}),
            Value::Table(t) => {
                let cols: Map<String, J> = t
                    .columns
                    .iter()
                    .map(|(n, c)| (n.clone(), json!(c)))
                    .collect();
                let order: Vec<&str> = t.columns.iter().map(|(n, _)| n.as_str()).collect();
                json!({"type": "table", "columns": cols, "order": order, "meta": t.meta})
            }
            Value::Camera(c) => serde(&**c)?,
            Value::Light(l) => serde(&**l)?,
            Value::Material(m) => serde(&**m)?,
            Value::Skeleton(s) => serde(&**s)?,
            Value::Model(m) => serde(&**m)?,
            Value::Scene(_) => return Err(EncodeError::Scene),
            Value::List(items) => J::Array(
                items
                    .iter()
                    .enumerate()
                    .map(|(i, x)| self.value(x, &format!("{sub}.{i}")))
                    .collect::<Result<_, _>>()?,
            ),
            plain => plain
                .to_json()
                .ok_or_else(|| EncodeError::NoJson(plain.socket_type()))?,
        })
    }

    fn mesh(&mut self, m: &Mesh, sub: &str) -> Result<J, EncodeError> {
        let counts: Vec<i32> = m.face_counts().iter().map(|&c| c as i32).collect();
        let idx: Vec<i32> = m.face_indices().iter().map(|&c| c as i32).collect();
        let mut o = Map::new();
        o.insert("type".into(), json!("mesh"));
        o.insert(
            "positions".into(),
            self.vec3s(&format!("{sub}.positions"), &m.positions)?,
        );
        o.insert(
            "face_counts".into(),
            self.array(
                &format!("{sub}.face_counts"),
                &NpyArray::from_i32(&[counts.len()], &counts),
            )?,
        );
        o.insert(
            "face_indices".into(),
            self.array(
                &format!("{sub}.face_indices"),
                &NpyArray::from_i32(&[idx.len()], &idx),
            )?,
        );
        if m.face_counts().iter().all(|&c| c == 3) {
            let a = NpyArray::from_i32(&[counts.len(), 3], &idx);
            o.insert(
                "triangles".into(),
                self.array(&format!("{sub}.triangles"), &a)?,
            );
        }
        if let Some(uv) = &m.uvs {
            let flat: Vec<f64> = uv.values.iter().flatten().copied().collect();
            let a = NpyArray::from_f64(&[uv.values.len(), 2], &flat);
            o.insert("uvs".into(), self.array(&format!("{sub}.uvs"), &a)?);
            o.insert("uv_domain".into(), json!(domain_name(uv.domain)));
        }
        if let Some(n) = &m.normals {
            o.insert(
                "normals".into(),
                self.vec3s(&format!("{sub}.normals"), &n.values)?,
            );
            o.insert("normal_domain".into(), json!(domain_name(n.domain)));
        }
        if let Some(c) = &m.colors {
            o.insert(
                "colors".into(),
                self.vec3s(&format!("{sub}.colors"), &c.values)?,
            );
            o.insert("color_domain".into(), json!(domain_name(c.domain)));
        }
        let mut attrs = Map::new();
        for (name, a) in &m.attributes {
            let file = format!("{sub}.a_{}", safe(name));
            let (domain, arr) = match a {
                AttributeData::Float(a) => {
                    (a.domain, NpyArray::from_f64(&[a.values.len()], &a.values))
                }
                AttributeData::Vec2(a) => {
                    let f: Vec<f64> = a.values.iter().flatten().copied().collect();
                    (a.domain, NpyArray::from_f64(&[a.values.len(), 2], &f))
                }
                AttributeData::Vec3(a) => {
                    let f: Vec<f64> = a.values.iter().flatten().copied().collect();
                    (a.domain, NpyArray::from_f64(&[a.values.len(), 3], &f))
                }
                AttributeData::Int(a) => {
                    let f: Vec<i32> = a.values.iter().map(|&x| x as i32).collect();
                    (a.domain, NpyArray::from_i32(&[a.values.len()], &f))
                }
            };
            attrs.insert(
                name.clone(),
                json!({"domain": domain_name(domain), "data": self.array(&file, &arr)?}),
            );
        }
        o.insert("attributes".into(), J::Object(attrs));
        Ok(J::Object(o))
    }
}

fn serde<T: serde::Serialize>(x: &T) -> Result<J, EncodeError> {
    Ok(serde_json::to_value(x)?)
}

/// A name made safe for a file name.
fn safe(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

fn domain_name(d: Domain) -> &'static str {
    match d {
        Domain::Vertex => "vertex",
        Domain::Corner => "corner",
        Domain::Face => "face",
    }
}
