//! `texture_map`: attaches a texture to a mesh through its UVs, by default a checkerboard,
//! the usual way to see a parameterization's distortion on the surface. `mesh_save` writes
//! the material as MTL + image next to the OBJ.

use cgnodes_api::prelude::*;
pub use cgnodes_geometry::checkerboard::*;

fn declare(b: &mut NodeBuilder) {
    b.doc("Attaches a texture (default: a generated checkerboard) to a mesh with UVs as its material.");
    b.add_input::<Mesh>("mesh");
    b.add_input::<Image>("image")
        .optional()
        .doc("The texture; a checkerboard when unconnected.");
    b.add_input::<i64>("checker_squares")
        .default(16i64)
        .range(1.0, 1024.0)
        .doc("Squares per side of the generated checkerboard.");
    b.add_input::<i64>("checker_size")
        .default(512i64)
        .range(8.0, 8192.0)
        .doc("Pixels per side of the generated checkerboard.");
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    if mesh.uvs.is_none() {
        return Err(NodeError::invalid(
            "mesh",
            "mesh has no UVs to map a texture through (run tutte or arap first)",
        ));
    }
    let img: Option<Arc<Image>> = ctx.input_opt("image")?;
    let squares: i64 = ctx.input("checker_squares")?;
    let size: i64 = ctx.input("checker_size")?;
    let (tex, name) = match img {
        Some(i) => (i, "texture"),
        None => {
            let s = size.clamp(8, 8192) as u32;
            let what = format!("a {s}x{s} checkerboard");
            let bytes = cgnodes_api::node::bytes_of(&[s as u64, s as u64, 16]);
            ctx.reserve_bytes("checker_size", &what, bytes)?;
            let squares = squares.clamp(1, 1024) as u32;
            (Arc::new(checkerboard(s, squares)), "checker")
        }
    };
    let base = mesh.material.as_deref().cloned().unwrap_or_default();
    let mat = Material {
        name: name.into(),
        base_color: [1.0, 1.0, 1.0],
        base_color_texture: Some(tex),
        ..base
    };
    let mut out = (*mesh).clone();
    out.material = Some(Arc::new(mat));
    ctx.set_output("mesh", out);
    Ok(())
}

/// Registers `texture_map`.
pub fn register(r: &mut Registry) {
    r.add("texture_map", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkerboard_has_the_requested_squares() {
        let img = checkerboard(64, 4);
        // bottom-left pixel is UV (0, 0): dark; one square to the right: light
        assert!(img.get(0, 63)[0] < 0.1);
        assert!(img.get(16, 63)[0] > 0.5);
        assert!(img.get(16, 47)[0] < 0.1);
        // count colour changes along the top row: 4 squares -> 3 changes
        let changes = (1..64)
            .filter(|&x| img.get(x, 0)[0] != img.get(x - 1, 0)[0])
            .count();
        assert_eq!(changes, 3);
    }
}
