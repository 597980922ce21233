//! `scene_load`: reads an OBJ file and its MTL materials into a `Scene` for the tracers,
//! one object per OBJ object/material group. MTL mapping: `Kd` is the diffuse albedo,
//! `Ke` the emitted radiance (one-sided, along the counter-clockwise normal, unless
//! `two_sided_emission`), `illum` 3 or 5 makes a mirror (tinted by `Ks`, else `Kd`),
//! `illum` 4, 6 or 7 a smooth dielectric with index `Ni` (1.5 if missing), `Ns` sets the
//! Phong roughness (r = sqrt(2 / (Ns + 2))) and `Ks` the specular weight the Whitted
//! tracer uses. Normals (`vn`) and UVs (`vt`) are kept for shading; MTL textures are not
//! read (give a `material` with a `texture` instead). The OBJ itself is read by the mesh domain's loader
//! (`load_obj_objects`), so its errors carry line numbers.

use cgnodes_api::prelude::*;
use cgnodes_formats::obj::{load_obj_objects, ObjError};
use std::path::{Path, PathBuf};

/// Why an OBJ file is not a scene, naming the file.
#[derive(Debug, thiserror::Error)]
pub enum SceneLoadError {
    /// The OBJ cannot be read.
    #[error("{}: {source}", path.display())]
    Obj {
        /// The OBJ file.
        path: PathBuf,
        /// What the reader found.
        source: ObjError,
    },
    /// Its material library cannot be read.
    #[error("{}: material library: {source}", path.display())]
    Materials {
        /// The OBJ file.
        path: PathBuf,
        /// What tobj found.
        source: tobj::LoadError,
    },
    /// An object names a material the libraries do not define.
    #[error("object '{0}' names a missing material")]
    MissingMaterial(String),
    /// The file has no faces.
    #[error("{}: no faces", .0.display())]
    NoFaces(PathBuf),
}

/// Converts one MTL material.
pub fn material_from_mtl(m: &tobj::Material, two_sided_emission: bool) -> Material {
    let kd = m.diffuse.unwrap_or([0.8; 3]);
    let ks = m.specular;
    let kind = match m.illumination_model {
        Some(3) | Some(5) => MaterialKind::Mirror,
        Some(4) | Some(6) | Some(7) => MaterialKind::Dielectric {
            ior: m
                .optical_density
                .filter(|x| x.is_finite() && *x > 0.0)
                .unwrap_or(1.5),
        },
        _ => MaterialKind::Diffuse,
    };
    let base_color = match kind {
        MaterialKind::Mirror => ks.filter(|c| c.iter().any(|x| *x > 0.0)).unwrap_or(kd),
        _ => kd,
    };
    let roughness = m
        .shininess
        .filter(|n| n.is_finite() && *n >= 0.0)
        .map(|n| (2.0 / (n + 2.0)).sqrt())
        .unwrap_or(0.5);
    Material {
        name: m.name.clone(),
        kind,
        base_color,
        roughness,
        metallic: ks
            .map(|c| c[0].max(c[1]).max(c[2]).clamp(0.0, 1.0))
            .unwrap_or(0.0),
        emission: m.emissive.unwrap_or([0.0; 3]),
        two_sided_emission,
        ..Default::default()
    }
}

/// Reads `path` (OBJ) and the MTL files it references into a scene without lights or
/// camera; faces keep their winding (counter-clockwise = front).
pub fn load_obj_scene(path: &Path, two_sided_emission: bool) -> Result<Scene, SceneLoadError> {
    let (blocks, mats) = load_obj_objects(path).map_err(|source| SceneLoadError::Obj {
        path: path.to_path_buf(),
        source,
    })?;
    let mats = mats.map_err(|source| SceneLoadError::Materials {
        path: path.to_path_buf(),
        source,
    })?;
    let mats: Vec<Arc<Material>> = mats
        .iter()
        .map(|m| Arc::new(material_from_mtl(m, two_sided_emission)))
        .collect();
    let mut scene = Scene::default();
    for b in blocks {
        let material = match b.material_id {
            Some(i) => Some(
                mats.get(i)
                    .cloned()
                    .ok_or_else(|| SceneLoadError::MissingMaterial(b.name.clone()))?,
            ),
            None => None,
        };
        // Normals (`vn`) and UVs (`vt`) are kept: the tracers shade with them.
        scene.objects.push(SceneObject {
            mesh: Arc::new(b.mesh),
            material,
        });
    }
    if scene.objects.is_empty() {
        return Err(SceneLoadError::NoFaces(path.to_path_buf()));
    }
    Ok(scene)
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Reads an OBJ + MTL file (Kd, Ke emission, illum/Ni) into a scene for the tracers.");
    // The MTL libraries (and their textures) enter the cache key with the OBJ.
    b.companions(cgnodes_formats::obj_companions::obj_companions);
    b.add_input::<String>("path")
        .file_in()
        .doc("OBJ file, relative to the graph's folder; its mtllib is read too.");
    b.add_input::<bool>("two_sided_emission")
        .default(false)
        .doc("Emit from both faces (MTL has no notion of this; default one-sided).");
    b.add_input::<Camera>("camera")
        .optional()
        .doc("Camera to store in the scene.");
    b.add_output::<Scene>("scene");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let p: String = ctx.input("path")?;
    let two: bool = ctx.input("two_sided_emission")?;
    let cam: Option<Arc<Camera>> = ctx.input_opt("camera")?;
    let path = ctx.input_path(&p);
    let mut scene = load_obj_scene(&path, two)
        .map_err(|e| NodeError::new(ErrorKind::Io, e.to_string()).at("path"))?;
    scene.camera = cam.map(|c| (*c).clone());
    let ne = scene
        .objects
        .iter()
        .filter(|o| {
            o.material
                .as_ref()
                .is_some_and(|m| m.emission.iter().any(|x| *x > 0.0))
        })
        .count();
    ctx.log(format!("{} objects, {ne} emissive", scene.objects.len()));
    ctx.set_output("scene", scene);
    Ok(())
}

/// Registers `scene_load`.
pub fn register(r: &mut Registry) {
    r.add("scene_load", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cornell_obj_loads_with_emission_and_albedo() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/cornell/cornell_box.obj");
        let s = load_obj_scene(&p, false).unwrap();
        let light: Vec<_> = s
            .objects
            .iter()
            .filter(|o| o.material.as_ref().unwrap().emission[0] > 0.0)
            .collect();
        assert_eq!(light.len(), 1);
        let m = light[0].material.as_ref().unwrap();
        assert!((m.emission[0] - 18.387).abs() < 1e-4);
        assert!((m.base_color[0] - 0.885809).abs() < 1e-6);
        let faces: usize = s.objects.iter().map(|o| o.mesh.num_faces()).sum();
        assert_eq!(faces, 36);
    }

    #[test]
    fn missing_file_is_an_error() {
        assert!(load_obj_scene(Path::new("/nonexistent/x.obj"), false).is_err());
    }
}
