//! `mesh_load`: reads a mesh from a file.

use crate::prelude::*;
use std::path::Path;

/// Reads an OBJ file with tobj: positions, polygon faces, and UVs and normals per corner.
/// All groups are merged into one mesh.
pub fn load_obj(path: &Path) -> Result<Mesh, String> {
    let opts = tobj::LoadOptions {
        triangulate: false,
        single_index: false,
        ..Default::default()
    };
    let (models, _) =
        tobj::load_obj(path, &opts).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut positions = Vec::new();
    let mut counts = Vec::new();
    let mut idx = Vec::new();
    let mut uvs = Vec::new();
    let mut has_uv = true;
    for m in &models {
        let mesh = &m.mesh;
        let base = positions.len() as u32;
        positions.extend(
            mesh.positions
                .chunks_exact(3)
                .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64]),
        );
        if mesh.face_arities.is_empty() {
            counts.extend(std::iter::repeat_n(3u32, mesh.indices.len() / 3));
        } else {
            counts.extend(&mesh.face_arities);
        }
        idx.extend(mesh.indices.iter().map(|&i| i + base));
        if mesh.texcoord_indices.len() == mesh.indices.len() && !mesh.texcoords.is_empty() {
            uvs.extend(mesh.texcoord_indices.iter().map(|&t| {
                [
                    mesh.texcoords[2 * t as usize] as f64,
                    mesh.texcoords[2 * t as usize + 1] as f64,
                ]
            }));
        } else {
            has_uv = false;
        }
    }
    let mut mesh =
        Mesh::new(positions, counts, idx).map_err(|e| format!("{}: {e}", path.display()))?;
    if has_uv && !uvs.is_empty() {
        mesh.uvs = Some(Attribute {
            domain: Domain::Corner,
            values: uvs,
        });
    }
    Ok(mesh)
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Reads a mesh from an OBJ file.").category("mesh");
    b.add_input::<String>("path")
        .file_in()
        .doc("Mesh file, relative to the graph's folder.");
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let p: String = ctx.input("path")?;
    let path = ctx.input_path(&p);
    let mesh = load_obj(&path).map_err(|e| NodeError::new(ErrorKind::Io, e).at("path"))?;
    ctx.set_output("mesh", mesh);
    Ok(())
}

/// Registers `mesh_load`.
pub fn register(r: &mut Registry) {
    r.add("mesh_load", declare, execute);
}
