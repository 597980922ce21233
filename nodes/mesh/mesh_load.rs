//! `mesh_load`: reads a mesh from OBJ, text USD (`.usda`), PLY (ASCII or binary) or OFF,
//! chosen by the file's extension.

use cgnodes_api::prelude::*;
pub use cgnodes_formats::mesh_file::{load_mesh, LoadOptions};

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
    let mesh = load_mesh(&path, &opts)
        .map_err(|e| NodeError::new(ErrorKind::Io, e.to_string()).at("path"))?;
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
