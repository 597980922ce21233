//! `mesh_save`: writes a mesh to a file under the output directory.

use crate::prelude::*;
use std::io::Write;

/// Writes OBJ text: `v`, `vt` (per vertex or per corner) and `f` lines.
pub fn write_obj(mesh: &Mesh, w: &mut dyn Write) -> std::io::Result<()> {
    writeln!(w, "# written by cgnodes")?;
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
    }
    let uv = mesh.uvs.as_ref().filter(|u| u.domain != Domain::Face);
    if let Some(uv) = uv {
        for t in &uv.values {
            writeln!(w, "vt {} {}", t[0], t[1])?;
        }
    }
    let mut c = 0usize;
    for f in mesh.faces() {
        write!(w, "f")?;
        for &v in f {
            match uv {
                Some(uv) if uv.domain == Domain::Vertex => write!(w, " {}/{}", v + 1, v + 1)?,
                Some(_) => write!(w, " {}/{}", v + 1, c + 1)?,
                None => write!(w, " {}", v + 1)?,
            }
            c += 1;
        }
        writeln!(w)?;
    }
    Ok(())
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Writes a mesh as OBJ under the output directory.")
        .category("mesh");
    b.sink();
    b.add_input::<Mesh>("mesh");
    b.add_input::<String>("path")
        .file_out()
        .doc("Output file; may contain {frame}.");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let p: String = ctx.input("path")?;
    let path = ctx.output_path("path", &p)?;
    ctx.write_with(&path, |w| write_obj(&mesh, w))
}

/// Registers `mesh_save`.
pub fn register(r: &mut Registry) {
    r.add("mesh_save", declare, execute);
}
