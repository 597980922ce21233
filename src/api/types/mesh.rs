use super::{Material, Topology};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::{Arc, OnceLock};

/// Where an attribute's values live, as in USD: one per vertex, one per face corner, or one per face.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Domain {
    Vertex,
    Corner,
    Face,
}

/// An attribute's values on a domain.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Attribute<T> {
    /// Where the values live.
    pub domain: Domain,
    /// One value per element of the domain.
    pub values: Vec<T>,
}

/// The data of a named attribute.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum AttributeData {
    Float(Attribute<f64>),
    Vec2(Attribute<[f64; 2]>),
    Vec3(Attribute<[f64; 3]>),
    Int(Attribute<i64>),
}

/// Why a mesh is malformed.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum MeshError {
    #[error("face {face} refers to vertex {index}, but the mesh has {count} vertices")]
    IndexOutOfRange {
        face: usize,
        index: u32,
        count: usize,
    },
    #[error("face {face} has {size} corners; a face needs at least 3")]
    TooFewCorners { face: usize, size: u32 },
    #[error("face {face} repeats vertex {index}")]
    RepeatedVertex { face: usize, index: u32 },
    #[error("vertex {vertex} has a non-finite coordinate {value:?}")]
    NonFinite { vertex: usize, value: [f64; 3] },
    #[error("face sizes add up to {sum} corners but {len} indices are given")]
    CornerCount { sum: usize, len: usize },
    #[error("attribute '{name}' has {got} values but its domain has {want}")]
    AttributeLength {
        name: String,
        got: usize,
        want: usize,
    },
}

/// A polygon mesh, laid out as USD lays it out: positions, face sizes and face vertex indices,
/// plus optional UVs, normals and colours per vertex or per corner, and named attributes.
///
/// The connectivity (`topology()`) is built once on first use and shared by every node that
/// reads the same mesh; changing the faces through `set_faces` discards it.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<[f64; 3]>,
    face_counts: Vec<u32>,
    face_indices: Vec<u32>,
    #[serde(skip)]
    face_starts: OnceLock<Vec<u32>>,
    /// Texture coordinates, per vertex or per corner.
    pub uvs: Option<Attribute<[f64; 2]>>,
    /// Normals, per vertex, corner or face.
    pub normals: Option<Attribute<[f64; 3]>>,
    /// Colours, per vertex, corner or face (linear RGB).
    pub colors: Option<Attribute<[f64; 3]>>,
    /// Named attributes (for example `fixed`, `stress`, per-face `distortion`).
    pub attributes: BTreeMap<String, AttributeData>,
    /// A material attached by `texture_map` or a loader (written as MTL + image by `mesh_save`).
    pub material: Option<Arc<Material>>,
    /// The skeleton binding of a skinned mesh (joint indices and weights per vertex), kept by
    /// `mesh_load` from a UsdSkel-bound `.usda` mesh and used by `skin` and `animate_mesh`.
    // Always serialized: the disk cache uses postcard, which cannot skip fields.
    #[serde(default)]
    pub skin: Option<Arc<super::SkinBinding>>,
    #[serde(skip)]
    topology: OnceLock<Arc<Topology>>,
}

impl Mesh {
    /// A mesh from positions and polygon faces given as sizes and indices (USD's
    /// `faceVertexCounts` and `faceVertexIndices`). Checks the indices.
    pub fn new(
        positions: Vec<[f64; 3]>,
        face_counts: Vec<u32>,
        face_indices: Vec<u32>,
    ) -> Result<Mesh, MeshError> {
        let m = Mesh {
            positions,
            face_counts,
            face_indices,
            ..Default::default()
        };
        m.check()?;
        Ok(m)
    }

    /// A triangle mesh.
    pub fn from_triangles(
        positions: Vec<[f64; 3]>,
        triangles: &[[u32; 3]],
    ) -> Result<Mesh, MeshError> {
        let counts = vec![3; triangles.len()];
        let idx = triangles.iter().flatten().copied().collect();
        Mesh::new(positions, counts, idx)
    }

    /// Checks indices, face sizes, finiteness and attribute lengths.
    pub fn check(&self) -> Result<(), MeshError> {
        let sum: usize = self.face_counts.iter().map(|&c| c as usize).sum();
        if sum != self.face_indices.len() {
            return Err(MeshError::CornerCount {
                sum,
                len: self.face_indices.len(),
            });
        }
        for (i, p) in self.positions.iter().enumerate() {
            if p.iter().any(|x| !x.is_finite()) {
                return Err(MeshError::NonFinite {
                    vertex: i,
                    value: *p,
                });
            }
        }
        let n = self.positions.len();
        // Repeated corners: a linear scan for small faces; large ones stamp each vertex with
        // the face number (a scan per corner was O(k²) and hung on one face with 100k corners).
        let mut stamp: Vec<u32> = Vec::new();
        for f in 0..self.num_faces() {
            let face = self.face(f);
            if face.len() < 3 {
                return Err(MeshError::TooFewCorners {
                    face: f,
                    size: face.len() as u32,
                });
            }
            let big = face.len() > 32;
            if big && stamp.is_empty() {
                stamp = vec![u32::MAX; n];
            }
            for (k, &v) in face.iter().enumerate() {
                if v as usize >= n {
                    return Err(MeshError::IndexOutOfRange {
                        face: f,
                        index: v,
                        count: n,
                    });
                }
                let repeated = if big {
                    std::mem::replace(&mut stamp[v as usize], f as u32) == f as u32
                } else {
                    face[..k].contains(&v)
                };
                if repeated {
                    return Err(MeshError::RepeatedVertex { face: f, index: v });
                }
            }
        }
        let want = |d: Domain| match d {
            Domain::Vertex => n,
            Domain::Corner => self.face_indices.len(),
            Domain::Face => self.face_counts.len(),
        };
        let check_len = |name: &str, d: Domain, got: usize| {
            if got != want(d) {
                Err(MeshError::AttributeLength {
                    name: name.to_string(),
                    got,
                    want: want(d),
                })
            } else {
                Ok(())
            }
        };
        if let Some(a) = &self.uvs {
            check_len("uv", a.domain, a.values.len())?;
        }
        if let Some(a) = &self.normals {
            check_len("normal", a.domain, a.values.len())?;
        }
        if let Some(a) = &self.colors {
            check_len("color", a.domain, a.values.len())?;
        }
        for (name, a) in &self.attributes {
            let (d, len) = match a {
                AttributeData::Float(a) => (a.domain, a.values.len()),
                AttributeData::Vec2(a) => (a.domain, a.values.len()),
                AttributeData::Vec3(a) => (a.domain, a.values.len()),
                AttributeData::Int(a) => (a.domain, a.values.len()),
            };
            check_len(name, d, len)?;
        }
        Ok(())
    }

    /// Number of faces.
    pub fn num_faces(&self) -> usize {
        self.face_counts.len()
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Face sizes (USD `faceVertexCounts`).
    pub fn face_counts(&self) -> &[u32] {
        &self.face_counts
    }

    /// Face vertex indices, all faces one after another (USD `faceVertexIndices`).
    pub fn face_indices(&self) -> &[u32] {
        &self.face_indices
    }

    /// Offset of each face's first corner in `face_indices`, plus the total at the end.
    pub fn face_starts(&self) -> &[u32] {
        self.face_starts.get_or_init(|| {
            let mut s = Vec::with_capacity(self.face_counts.len() + 1);
            let mut acc = 0u32;
            s.push(0);
            for &c in &self.face_counts {
                acc += c;
                s.push(acc);
            }
            s
        })
    }

    /// The vertex indices of face `f`.
    pub fn face(&self, f: usize) -> &[u32] {
        let s = self.face_starts();
        &self.face_indices[s[f] as usize..s[f + 1] as usize]
    }

    /// Iterates over faces as index slices.
    pub fn faces(&self) -> impl Iterator<Item = &[u32]> + '_ {
        (0..self.num_faces()).map(move |f| self.face(f))
    }

    /// Replaces the faces. Discards the connectivity and any per-corner or per-face data that
    /// no longer fits.
    pub fn set_faces(&mut self, face_counts: Vec<u32>, face_indices: Vec<u32>) {
        self.face_counts = face_counts;
        self.face_indices = face_indices;
        self.face_starts = OnceLock::new();
        self.topology = OnceLock::new();
        let nc = self.face_indices.len();
        let nf = self.face_counts.len();
        let fits = |d: Domain, len: usize| match d {
            Domain::Vertex => true,
            Domain::Corner => len == nc,
            Domain::Face => len == nf,
        };
        if self
            .uvs
            .as_ref()
            .is_some_and(|a| !fits(a.domain, a.values.len()))
        {
            self.uvs = None;
        }
        if self
            .normals
            .as_ref()
            .is_some_and(|a| !fits(a.domain, a.values.len()))
        {
            self.normals = None;
        }
        if self
            .colors
            .as_ref()
            .is_some_and(|a| !fits(a.domain, a.values.len()))
        {
            self.colors = None;
        }
        self.attributes.retain(|_, a| match a {
            AttributeData::Float(a) => fits(a.domain, a.values.len()),
            AttributeData::Vec2(a) => fits(a.domain, a.values.len()),
            AttributeData::Vec3(a) => fits(a.domain, a.values.len()),
            AttributeData::Int(a) => fits(a.domain, a.values.len()),
        });
    }

    /// Whether every face is a triangle.
    pub fn is_triangle_mesh(&self) -> bool {
        self.face_counts.iter().all(|&c| c == 3)
    }

    /// The faces as triangles, or `None` when some face is not a triangle
    /// (see `triangulated()` for polygon meshes).
    pub fn triangles(&self) -> Option<Vec<[u32; 3]>> {
        if !self.is_triangle_mesh() {
            return None;
        }
        Some(
            self.face_indices
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
        )
    }

    /// A copy with every polygon split into a fan of triangles from its first corner;
    /// per-corner and per-face data follow their corners and faces. Returns the mesh unchanged
    /// (shared) when it is already all triangles.
    pub fn triangulated(self: &Arc<Self>) -> Arc<Mesh> {
        if self.is_triangle_mesh() {
            return self.clone();
        }
        let mut counts = Vec::new();
        let mut idx = Vec::new();
        let mut corner_src = Vec::new(); // source corner of each new corner
        let mut face_src = Vec::new();
        for (f, corners) in super::topology::fan_corners(&self.face_counts) {
            counts.push(3);
            for c in corners {
                idx.push(self.face_indices[c]);
                corner_src.push(c);
            }
            face_src.push(f);
        }
        let remap = |d: Domain| -> Option<&Vec<usize>> {
            match d {
                Domain::Corner => Some(&corner_src),
                Domain::Face => Some(&face_src),
                Domain::Vertex => None,
            }
        };
        fn re<T: Clone>(a: &Attribute<T>, map: Option<&Vec<usize>>) -> Attribute<T> {
            match map {
                None => a.clone(),
                Some(m) => Attribute {
                    domain: a.domain,
                    values: m.iter().map(|&i| a.values[i].clone()).collect(),
                },
            }
        }
        let mut out = Mesh {
            positions: self.positions.clone(),
            face_counts: counts,
            face_indices: idx,
            material: self.material.clone(),
            ..Default::default()
        };
        out.uvs = self.uvs.as_ref().map(|a| re(a, remap(a.domain)));
        out.normals = self.normals.as_ref().map(|a| re(a, remap(a.domain)));
        out.colors = self.colors.as_ref().map(|a| re(a, remap(a.domain)));
        for (k, a) in &self.attributes {
            let na = match a {
                AttributeData::Float(a) => AttributeData::Float(re(a, remap(a.domain))),
                AttributeData::Vec2(a) => AttributeData::Vec2(re(a, remap(a.domain))),
                AttributeData::Vec3(a) => AttributeData::Vec3(re(a, remap(a.domain))),
                AttributeData::Int(a) => AttributeData::Int(re(a, remap(a.domain))),
            };
            out.attributes.insert(k.clone(), na);
        }
        Arc::new(out)
    }

    /// The connectivity: edges, boundary loops, one-rings, components. Built on first use.
    pub fn topology(&self) -> &Arc<Topology> {
        self.topology
            .get_or_init(|| Arc::new(Topology::build(self)))
    }

    /// Per-vertex UVs, when the mesh has them per vertex (or per corner but consistent
    /// at every vertex).
    pub fn vertex_uvs(&self) -> Option<Vec<[f64; 2]>> {
        let uv = self.uvs.as_ref()?;
        match uv.domain {
            Domain::Vertex => Some(uv.values.clone()),
            Domain::Face => None,
            Domain::Corner => {
                let mut out: Vec<Option<[f64; 2]>> = vec![None; self.positions.len()];
                for (c, &v) in self.face_indices.iter().enumerate() {
                    let t = uv.values[c];
                    match out[v as usize] {
                        None => out[v as usize] = Some(t),
                        Some(o) if o == t => {}
                        Some(_) => return None,
                    }
                }
                out.into_iter().map(|o| o.or(Some([0.0, 0.0]))).collect()
            }
        }
    }

    /// Axis-aligned bounding box (min, max); zeros for an empty mesh.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        if self.positions.is_empty() {
            return ([0.0; 3], [0.0; 3]);
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &self.positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_indices() {
        let p = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(matches!(
            Mesh::from_triangles(p.clone(), &[[0, 1, 3]]),
            Err(MeshError::IndexOutOfRange {
                face: 0,
                index: 3,
                ..
            })
        ));
        assert!(matches!(
            Mesh::from_triangles(p.clone(), &[[0, 1, 1]]),
            Err(MeshError::RepeatedVertex { .. })
        ));
        let mut bad = p.clone();
        bad[1][2] = f64::NAN;
        assert!(matches!(
            Mesh::from_triangles(bad, &[[0, 1, 2]]),
            Err(MeshError::NonFinite { vertex: 1, .. })
        ));
    }

    /// Large faces take the stamped path of the repeated-corner check: a repeat is still
    /// found (in the second large face, so stale stamps of the first must not count), and
    /// two large faces sharing vertices are fine.
    #[test]
    fn repeated_corners_in_large_faces() {
        let p: Vec<[f64; 3]> = (0..100).map(|i| [i as f64, (i * i) as f64, 0.0]).collect();
        let a: Vec<u32> = (0..100).collect();
        let mut b: Vec<u32> = (0..100).rev().collect();
        let ok = Mesh::new(p.clone(), vec![100, 100], [a.clone(), b.clone()].concat());
        assert!(ok.is_ok());
        b[70] = b[10];
        let e = Mesh::new(p, vec![100, 100], [a, b].concat()).unwrap_err();
        assert!(
            matches!(e, MeshError::RepeatedVertex { face: 1, index: 89 }),
            "{e:?}"
        );
    }

    #[test]
    fn triangulates_quads_keeping_corner_uvs() {
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let mut m = Mesh::new(p, vec![4], vec![0, 1, 2, 3]).unwrap();
        m.uvs = Some(Attribute {
            domain: Domain::Corner,
            values: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        });
        let t = Arc::new(m).triangulated();
        assert_eq!(t.triangles().unwrap(), vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(t.uvs.as_ref().unwrap().values[5], [0.0, 1.0]);
        t.check().unwrap();
    }
}
