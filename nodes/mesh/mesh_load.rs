//! `mesh_load`: reads a mesh from OBJ, text USD (`.usda`), PLY (ASCII or binary) or OFF,
//! chosen by the file's extension.

use crate::prelude::*;
use std::path::Path;

/// What `load_mesh` should pick out of a file.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// USD prim path (`/Balls/Balls`); empty: the first Mesh.
    pub prim: String,
    /// OBJ group or object name; empty: all groups merged.
    pub group: String,
    /// Apply USD `xformOp`s of the prim and its ancestors.
    pub apply_transform: bool,
}

/// Reads a mesh file, choosing the format by extension (`obj`, `usda`/`usd`, `ply`, `off`).
/// Errors name the file and, for text formats, the offending line.
pub fn load_mesh(path: &Path, opts: &LoadOptions) -> Result<Mesh, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let name = path.display();
    if !path.exists() {
        return Err(format!("{name}: file not found"));
    }
    let read_text =
        || std::fs::read_to_string(path).map_err(|e| format!("{name}: cannot read: {e}"));
    let r = match ext.as_str() {
        "obj" => super::obj::load_obj(path, &opts.group),
        "usda" | "usd" => {
            let text = read_text()?;
            super::usda::read_usda(&text, &opts.prim, opts.apply_transform)
        }
        "ply" => {
            let bytes = std::fs::read(path).map_err(|e| format!("{name}: cannot read: {e}"))?;
            super::ply::read_ply(&bytes)
        }
        "off" => super::off::read_off(&read_text()?),
        other => {
            return Err(format!(
                "{name}: unknown mesh format '.{other}' (obj, usda, ply, off are read)"
            ))
        }
    };
    r.map_err(|e| format!("{name}: {e}"))
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Reads a mesh from OBJ, USDA, PLY or OFF (by extension).");
    b.add_input::<String>("path")
        .file_in()
        .doc("Mesh file, relative to the graph's folder (or an --assets folder).");
    b.add_input::<String>("prim")
        .default("")
        .doc("USD prim path such as /Balls/Balls; empty: the first Mesh.");
    b.add_input::<String>("group")
        .default("")
        .doc("OBJ group/object to load; empty: all groups merged.");
    b.add_input::<bool>("transform")
        .default(true)
        .doc("Apply the USD prim's and its parents' xformOp transforms.");
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let p: String = ctx.input("path")?;
    let path = ctx.input_path(&p);
    let opts = LoadOptions {
        prim: ctx.input("prim")?,
        group: ctx.input("group")?,
        apply_transform: ctx.input("transform")?,
    };
    let mesh = load_mesh(&path, &opts).map_err(|e| NodeError::new(ErrorKind::Io, e).at("path"))?;
    let topo = mesh.topology();
    if !topo.is_manifold() {
        ctx.log(format!(
            "warning: mesh is not manifold ({} edges with more than two faces, {} non-manifold vertices, {} edges with inconsistent orientation)",
            topo.nonmanifold_edges.len(),
            topo.nonmanifold_vertices.len(),
            topo.misoriented_edges.len()
        ));
    }
    ctx.log(format!(
        "{} vertices, {} faces",
        mesh.num_vertices(),
        mesh.num_faces()
    ));
    ctx.set_output("mesh", mesh);
    Ok(())
}

/// Registers `mesh_load`.
pub fn register(r: &mut Registry) {
    r.add("mesh_load", declare, execute);
}
