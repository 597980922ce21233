//! `mesh_save`: writes a mesh under the output directory as OBJ (plus MTL and texture PNG
//! when the mesh carries a material), PLY, USDA or OFF, chosen by the extension.

use cgnodes_api::prelude::*;
use std::path::Path;

/// Encodes a linear RGBA image as an 8-bit sRGB PNG (IEC 61966-2-1 transfer function) with
/// `image_save`'s encoder; a `+inf` colour channel stays white here (the encoder writes it
/// as 0), as texture files written by `mesh_save` always had.
pub fn png_bytes(img: &Image) -> Result<Vec<u8>, String> {
    use cgnodes_formats::image_file::{encode_image, ImageFileFormat};
    let mut img = img.clone();
    for p in &mut img.pixels {
        for c in &mut p[..3] {
            if *c == f32::INFINITY {
                *c = 1.0;
            }
        }
    }
    encode_image(&img, ImageFileFormat::Png, 0.0, 0.0)
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Writes a mesh as OBJ (+MTL, texture), PLY, USDA or OFF under the output directory.");
    b.sink();
    b.add_input::<Mesh>("mesh");
    b.add_input::<String>("path")
        .file_out()
        .doc("Output file (.obj, .ply, .usda, .off); may contain {frame}.");
    b.add_input::<String>("prim")
        .default("/mesh/mesh")
        .doc("USDA only: prim path of the Mesh (parents become Xforms).");
    b.add_input::<bool>("animated")
        .default(false)
        .doc("USDA only: one file for all frames, points (and normals) as timeSamples at the frame number.");
    b.add_input::<bool>("binary")
        .default(false)
        .doc("PLY only: binary little endian instead of ASCII.");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let p: String = ctx.input("path")?;
    let prim: String = ctx.input("prim")?;
    let binary: bool = ctx.input("binary")?;
    let animated: bool = ctx.input("animated")?;
    let path = ctx.output_path("path", &p)?;
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let written = match ext.as_str() {
        "obj" => save_obj(ctx, &mesh, &path),
        "ply" => ctx.write_with(&path, |w| super::ply::write_ply(&mesh, binary, w)),
        "usda" | "usd" if animated => save_animated(ctx, &mesh, &p, &path, &prim),
        "usda" | "usd" => ctx.write_with(&path, |w| super::usda::write_usda(&mesh, &prim, w)),
        "off" => ctx.write_with(&path, |w| super::off::write_off(&mesh, w)),
        other => Err(NodeError::invalid(
            "path",
            format!("unknown mesh format '.{other}' (obj, ply, usda, off are written)"),
        )),
    };
    written?;
    // The run report previews the mesh from memory instead of reading the file back.
    ctx.wrote_from(&path, Value::Mesh(mesh));
    Ok(())
}

/// Adds this frame's points (and normals) to the animated layer at `path` (see
/// `usda::write_anim`), starting a new one when the file is absent or holds another mesh.
fn save_animated(
    ctx: &mut ExecContext,
    mesh: &Mesh,
    raw: &str,
    path: &Path,
    prim: &str,
) -> Result<(), NodeError> {
    use super::usda::write_anim::{read_samples, write_animated};
    if raw.contains("{frame}") {
        return Err(NodeError::invalid(
            "path",
            "animated writes every frame into one file; remove {frame} from the path",
        ));
    }
    let old = std::fs::read_to_string(path).ok();
    let mut samples = old
        .as_deref()
        .and_then(|t| read_samples(t, prim, mesh))
        .unwrap_or_default();
    if old.is_some() && samples.times.is_empty() {
        ctx.log(format!(
            "{}: not an animated layer of this mesh; starting a new one",
            path.display()
        ));
    }
    let normals = mesh
        .normals
        .as_ref()
        .filter(|n| n.domain == Domain::Vertex || n.domain == Domain::Corner)
        .map(|n| n.values.clone());
    samples.insert(ctx.frame() as f64, mesh.positions.clone(), normals);
    ctx.write_with(path, |w| write_animated(mesh, prim, &samples, w))
}

fn save_obj(ctx: &mut ExecContext, mesh: &Mesh, path: &Path) -> Result<(), NodeError> {
    let Some(mat) = mesh.material.as_deref() else {
        return ctx.write_with(path, |w| super::obj::write_obj(mesh, None, w));
    };
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("mesh")
        .to_string();
    let mtl_file = format!("{stem}.mtl");
    let name = super::obj::mtl_name(mat);
    let mut tex_file = None;
    if let Some(img) = &mat.base_color_texture {
        let t = format!(
            "{stem}_{}.png",
            cgnodes_formats::usda::usd_identifier(&name)
        );
        let bytes = png_bytes(img).map_err(|e| NodeError::io(&path.with_file_name(&t), e))?;
        ctx.write_file(&path.with_file_name(&t), &bytes)?;
        tex_file = Some(t);
    }
    if tex_file.is_some() && mesh.uvs.is_none() {
        ctx.log("warning: the material has a texture but the mesh has no UVs");
    }
    ctx.write_with(&path.with_file_name(&mtl_file), |w| {
        super::obj::write_mtl(mat, tex_file.as_deref(), w)
    })?;
    ctx.write_with(path, |w| {
        super::obj::write_obj(mesh, Some((&mtl_file, &name)), w)
    })
}

/// Registers `mesh_save`.
pub fn register(r: &mut Registry) {
    r.add("mesh_save", declare, execute);
}

#[cfg(test)]
mod tests {
    /// The encoding `png_bytes` had before it used `encode_image`, as a reference.
    fn reference_png(img: &super::Image) -> Vec<u8> {
        let enc = |x: f32| -> u8 {
            let x = x.clamp(0.0, 1.0);
            let s = if x <= 0.003_130_8 {
                12.92 * x
            } else {
                1.055 * x.powf(1.0 / 2.4) - 0.055
            };
            (s * 255.0 + 0.5) as u8
        };
        let mut buf = image::RgbaImage::new(img.width, img.height);
        for (i, p) in buf.pixels_mut().enumerate() {
            let c = img.pixels[i];
            *p = image::Rgba([
                enc(c[0]),
                enc(c[1]),
                enc(c[2]),
                (c[3].clamp(0.0, 1.0) * 255.0 + 0.5) as u8,
            ]);
        }
        let mut out = std::io::Cursor::new(Vec::new());
        buf.write_to(&mut out, image::ImageFormat::Png).unwrap();
        out.into_inner()
    }

    #[test]
    fn png_bytes_match_the_former_encoding() {
        let special = [0.0, -0.0, 1.0, 0.5, 0.002, 2.0, -1.0, f32::NAN];
        let special = special
            .into_iter()
            .chain([f32::INFINITY, f32::NEG_INFINITY]);
        let mut pixels: Vec<[f32; 4]> = special.map(|v| [v, v, v, v]).collect();
        pixels.extend((0..1014).map(|i| {
            let x = i as f32 / 1013.0;
            [x, 1.0 - x, x * x, 0.5 + 0.5 * x]
        }));
        let img = super::Image {
            width: 32,
            height: 32,
            pixels,
        };
        assert_eq!(super::png_bytes(&img).unwrap(), reference_png(&img));
    }
}
