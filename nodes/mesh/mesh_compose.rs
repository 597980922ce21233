//! `mesh_decompose` and `mesh_compose`: a mesh split into Framework3D-style buffers
//! (vertices, face sizes, face indices, normals, texcoords) and put back together, so that
//! imported Framework3D graphs that edit buffers run unchanged.

use cgnodes_api::prelude::*;

/// The buffers of a mesh, as Framework3D's `geom_mesh_decompose` gives them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshBuffers {
    /// Vertex positions.
    pub vertices: Vec<[f64; 3]>,
    /// Face sizes.
    pub face_counts: Vec<i64>,
    /// Face vertex indices.
    pub face_indices: Vec<i64>,
    /// Normals (per vertex, corner or face; empty when absent).
    pub normals: Vec<[f64; 3]>,
    /// Texture coordinates (per vertex or corner; empty when absent).
    pub texcoords: Vec<[f64; 2]>,
}

/// Splits a mesh into buffers.
pub fn decompose(mesh: &Mesh) -> MeshBuffers {
    MeshBuffers {
        vertices: mesh.positions.clone(),
        face_counts: mesh.face_counts().iter().map(|&c| c as i64).collect(),
        face_indices: mesh.face_indices().iter().map(|&c| c as i64).collect(),
        normals: mesh
            .normals
            .as_ref()
            .map(|a| a.values.clone())
            .unwrap_or_default(),
        texcoords: mesh
            .uvs
            .as_ref()
            .map(|a| a.values.clone())
            .unwrap_or_default(),
    }
}

/// Why buffers do not make a mesh.
#[derive(Debug, thiserror::Error)]
pub enum ComposeError {
    /// A count or index that is negative or over `u32`.
    #[error("{what} holds {value}")]
    OutOfRange {
        /// The buffer: "face_counts" or "face_indices".
        what: &'static str,
        /// The value.
        value: i64,
    },
    /// The faces do not make a valid mesh.
    #[error("{0}")]
    Mesh(#[from] MeshError),
    /// A per-element buffer whose length matches no domain.
    #[error("{what} has {len} values; expected one per vertex ({vertices}), corner ({corners}) or face ({faces})")]
    Length {
        /// The buffer: "normals" or "texcoords".
        what: &'static str,
        /// Its length.
        len: usize,
        /// The mesh's vertex count.
        vertices: usize,
        /// Its corner count.
        corners: usize,
        /// Its face count.
        faces: usize,
    },
    /// Texture coordinates with one value per face.
    #[error("texcoords per face are not supported")]
    FaceTexcoords,
}

/// The domain whose size is `len`, preferring vertex, then corner, then face.
fn domain_of(mesh: &Mesh, len: usize, what: &'static str) -> Result<Domain, ComposeError> {
    if len == mesh.num_vertices() {
        Ok(Domain::Vertex)
    } else if len == mesh.face_indices().len() {
        Ok(Domain::Corner)
    } else if len == mesh.num_faces() {
        Ok(Domain::Face)
    } else {
        Err(ComposeError::Length {
            what,
            len,
            vertices: mesh.num_vertices(),
            corners: mesh.face_indices().len(),
            faces: mesh.num_faces(),
        })
    }
}

/// Builds a mesh from buffers, checking indices; normals and texcoords are placed on the
/// domain their length matches (vertex, corner or face).
pub fn compose(b: &MeshBuffers) -> Result<Mesh, ComposeError> {
    let to_u32 = |v: &[i64], what: &'static str| {
        v.iter()
            .map(|&x| u32::try_from(x).map_err(|_| ComposeError::OutOfRange { what, value: x }))
            .collect::<Result<Vec<u32>, ComposeError>>()
    };
    let mut m = Mesh::new(
        b.vertices.clone(),
        to_u32(&b.face_counts, "face_counts")?,
        to_u32(&b.face_indices, "face_indices")?,
    )?;
    if !b.normals.is_empty() {
        let d = domain_of(&m, b.normals.len(), "normals")?;
        m.normals = Some(Attribute {
            domain: d,
            values: b.normals.clone(),
        });
    }
    if !b.texcoords.is_empty() {
        let d = domain_of(&m, b.texcoords.len(), "texcoords")?;
        if d == Domain::Face {
            return Err(ComposeError::FaceTexcoords);
        }
        m.uvs = Some(Attribute {
            domain: d,
            values: b.texcoords.clone(),
        });
    }
    Ok(m)
}

fn declare_decompose(b: &mut NodeBuilder) {
    b.doc("Splits a mesh into vertex, face, normal and texcoord buffers (Framework3D's Mesh Decompose).");
    b.add_input::<Mesh>("mesh");
    b.add_output::<Vec<[f64; 3]>>("vertices");
    b.add_output::<Vec<i64>>("face_counts");
    b.add_output::<Vec<i64>>("face_indices");
    b.add_output::<Vec<[f64; 3]>>("normals");
    b.add_output::<Vec<[f64; 2]>>("texcoords");
}

fn execute_decompose(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let b = decompose(&mesh);
    ctx.set_output("vertices", b.vertices);
    ctx.set_output("face_counts", b.face_counts);
    ctx.set_output("face_indices", b.face_indices);
    ctx.set_output("normals", b.normals);
    ctx.set_output("texcoords", b.texcoords);
    Ok(())
}

fn declare_compose(b: &mut NodeBuilder) {
    b.doc("Builds a mesh from vertex, face, normal and texcoord buffers (Framework3D's Mesh Compose).");
    b.add_input::<Vec<[f64; 3]>>("vertices");
    b.add_input::<Vec<i64>>("face_counts");
    b.add_input::<Vec<i64>>("face_indices");
    b.add_input::<Vec<[f64; 3]>>("normals")
        .optional()
        .doc("Per vertex, corner or face (by length).");
    b.add_input::<Vec<[f64; 2]>>("texcoords")
        .optional()
        .doc("Per vertex or corner (by length).");
    b.add_output::<Mesh>("mesh");
}

fn execute_compose(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let b = MeshBuffers {
        vertices: ctx.input("vertices")?,
        face_counts: ctx.input("face_counts")?,
        face_indices: ctx.input("face_indices")?,
        normals: ctx.input_opt("normals")?.unwrap_or_default(),
        texcoords: ctx.input_opt("texcoords")?.unwrap_or_default(),
    };
    let m = compose(&b).map_err(|e| NodeError::invalid("face_indices", e.to_string()))?;
    ctx.set_output("mesh", m);
    Ok(())
}

/// Registers `mesh_decompose` and `mesh_compose`.
pub fn register(r: &mut Registry) {
    r.add("mesh_decompose", declare_decompose, execute_decompose);
    r.add("mesh_compose", declare_compose, execute_compose);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decompose_compose_is_identity_and_bad_buffers_fail() {
        let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let mut m = Mesh::from_triangles(p, &[[0, 1, 2]]).unwrap();
        m.uvs = Some(Attribute {
            domain: Domain::Vertex,
            values: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
        });
        let b = decompose(&m);
        let r = compose(&b).unwrap();
        assert_eq!(r.positions, m.positions);
        assert_eq!(r.uvs, m.uvs);
        let mut bad = b.clone();
        bad.texcoords.pop();
        assert!(compose(&bad)
            .unwrap_err()
            .to_string()
            .contains("texcoords has 2"));
        bad = b;
        bad.face_indices[2] = 5;
        assert!(compose(&bad).is_err());
    }
}
