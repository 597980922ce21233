//! `scene`: gathers meshes with materials, lights and a camera into one `Scene` for the
//! rasterizer and the tracers.

use cgnodes_api::prelude::*;

/// Builds a scene: `base` (if any) first, then `meshes`, each with `materials[i]` when
/// given (else `None`: the renderer uses the mesh's own material or the default), the
/// `lights` appended, and `camera` replacing the base camera when given.
pub fn build_scene(
    base: Option<&Scene>,
    meshes: &[Arc<Mesh>],
    materials: &[Arc<Material>],
    lights: &[Arc<Light>],
    camera: Option<&Camera>,
) -> Scene {
    let mut s = base.cloned().unwrap_or_default();
    for (i, m) in meshes.iter().enumerate() {
        s.objects.push(SceneObject {
            mesh: m.clone(),
            material: materials.get(i).cloned(),
        });
    }
    s.lights.extend(lights.iter().map(|l| (**l).clone()));
    if let Some(c) = camera {
        s.camera = Some(c.clone());
    }
    s
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Gathers meshes with materials, lights and a camera into a scene.");
    b.add_input::<Vec<Mesh>>("meshes")
        .optional()
        .doc("Meshes (several links allowed).");
    b.add_input::<Vec<Material>>("materials").optional().doc(
        "Materials matched to meshes by index; missing ones use the mesh's own or the default.",
    );
    b.add_input::<Vec<Light>>("lights")
        .optional()
        .doc("Light sources.");
    b.add_input::<Camera>("camera")
        .optional()
        .doc("Camera (replaces the merged scene's camera).");
    b.add_input::<Scene>("scene")
        .optional()
        .doc("A scene merged in first.");
    b.add_output::<Scene>("scene");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let meshes: Vec<Arc<Mesh>> = ctx.input_opt("meshes")?.unwrap_or_default();
    let materials: Vec<Arc<Material>> = ctx.input_opt("materials")?.unwrap_or_default();
    let lights: Vec<Arc<Light>> = ctx.input_opt("lights")?.unwrap_or_default();
    let camera: Option<Arc<Camera>> = ctx.input_opt("camera")?;
    let base: Option<Arc<Scene>> = ctx.input_opt("scene")?;
    if materials.len() > meshes.len() {
        ctx.log(format!(
            "{} materials for {} meshes: the extra materials are unused",
            materials.len(),
            meshes.len()
        ));
    }
    let s = build_scene(
        base.as_deref(),
        &meshes,
        &materials,
        &lights,
        camera.as_deref(),
    );
    ctx.set_output("scene", s);
    Ok(())
}

/// Registers `scene`.
pub fn register(r: &mut Registry) {
    r.add("scene", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn run(inputs: BTreeMap<String, Value>) -> Scene {
        match &super::super::run_node("scene", inputs).unwrap()["scene"] {
            Value::Scene(s) => (**s).clone(),
            _ => panic!("not a scene"),
        }
    }

    fn tri() -> Mesh {
        Mesh::from_triangles(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            &[[0, 1, 2]],
        )
        .unwrap()
    }

    #[test]
    fn materials_match_meshes_by_index_and_base_scene_comes_first() {
        let red = Material {
            base_color: [1.0, 0.0, 0.0],
            ..Default::default()
        };
        let base = Scene {
            lights: vec![Light::Directional {
                direction: [0.0, -1.0, 0.0],
                color: [1.0; 3],
                intensity: 1.0,
            }],
            camera: Some(Camera::default()),
            ..Scene::from_mesh(Arc::new(tri()))
        };
        let mut inp = BTreeMap::new();
        inp.insert(
            "meshes".into(),
            Value::from(vec![Arc::new(tri()), Arc::new(tri())]),
        );
        inp.insert("materials".into(), Value::from(vec![Arc::new(red.clone())]));
        inp.insert(
            "lights".into(),
            Value::from(Light::Point {
                position: [0.0; 3],
                color: [1.0; 3],
                intensity: 1.0,
            }),
        );
        inp.insert("scene".into(), Value::from(base));
        let s = run(inp);
        assert_eq!(s.objects.len(), 3);
        assert!(s.objects[0].material.is_none());
        assert_eq!(s.objects[1].material.as_deref(), Some(&red));
        assert!(s.objects[2].material.is_none());
        assert_eq!(s.lights.len(), 2);
        assert!(matches!(s.lights[0], Light::Directional { .. }));
        assert_eq!(s.camera, Some(Camera::default()));
    }

    #[test]
    fn empty_scene_and_camera_override() {
        let s = run(BTreeMap::new());
        assert!(s.objects.is_empty() && s.lights.is_empty() && s.camera.is_none());
        let cam = Camera {
            width: 64,
            ..Default::default()
        };
        let mut inp = BTreeMap::new();
        inp.insert("camera".into(), Value::from(cam.clone()));
        assert_eq!(run(inp).camera, Some(cam));
    }
}
