//! Stage round trips, the framework's light transforms, the default framing and particles.

use super::model::{translation, LightKind, Stage, StageMesh, StagePoints, UpAxis};
use super::read::read_stage;
use super::scene::{camera_prim, default_camera, stage_to_scene};
use super::stage_nodes::{framework_light, StageLightType};
use super::write::write_stage;
use cgnodes_api::types::{Attribute, Domain, Light, Mesh};

fn quad() -> Mesh {
    let mut m = Mesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.5],
            [0.0, 1.0, 0.25],
        ],
        vec![4],
        vec![0, 1, 2, 3],
    )
    .unwrap();
    m.colors = Some(Attribute {
        domain: Domain::Vertex,
        values: vec![
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.5, 0.5, 0.5],
        ],
    });
    m.uvs = Some(Attribute {
        domain: Domain::Corner,
        values: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
    });
    m
}

fn sample_stage() -> Stage {
    let dome = framework_light(
        StageLightType::Dome,
        "DomeLight",
        [0.0; 3],
        [0.0, 0.0, 30.0],
        [1.0, 1.0, 2.013],
        1.0,
        [0.0; 3],
        "garden.exr",
    );
    let point = framework_light(
        StageLightType::Point,
        "Light",
        [1.0, -2.0, 3.5],
        [0.0; 3],
        [0.25, 0.5, 1.0],
        2.0,
        [0.1, 0.0, 0.0],
        "",
    );
    let sun = framework_light(
        StageLightType::Distant,
        "Sun",
        [0.0; 3],
        [90.0, 0.0, 0.0],
        [1.0; 3],
        3.0,
        [1.0, 0.0, 0.0],
        "",
    );
    Stage {
        up_axis: UpAxis::Z,
        meshes: vec![StageMesh {
            path: "/geometry2".into(),
            mesh: quad(),
        }],
        points: vec![StagePoints {
            path: "/geometry".into(),
            points: vec![[0.1, 0.2, 0.3], [0.4, 0.5, 0.6], [-1.0, 2.0, 0.125]],
            widths: vec![0.05],
            colors: Some(vec![[0.1, 0.2, 0.9], [0.9, 0.2, 0.1], [0.5, 0.5, 0.5]]),
        }],
        lights: vec![dome, point, sun],
        camera: None,
    }
}

#[test]
fn a_written_stage_reads_back_the_same() {
    let mut s = sample_stage();
    let cam = default_camera([0.0; 3], [1.0; 3], UpAxis::Z, 64, 48);
    s.camera = Some(camera_prim(&cam, "/camera"));
    let text = write_stage(&s);
    let r = read_stage(&text).unwrap();
    assert_eq!(r.up_axis, UpAxis::Z);
    assert_eq!(r.meshes.len(), 1);
    assert_eq!(r.meshes[0].path, "/geometry2");
    assert_eq!(r.meshes[0].mesh.positions, s.meshes[0].mesh.positions);
    assert_eq!(
        r.meshes[0].mesh.face_indices(),
        s.meshes[0].mesh.face_indices()
    );
    assert_eq!(
        r.meshes[0].mesh.colors.as_ref().unwrap().values,
        s.meshes[0].mesh.colors.as_ref().unwrap().values
    );
    assert_eq!(
        r.meshes[0].mesh.uvs.as_ref().unwrap().values,
        s.meshes[0].mesh.uvs.as_ref().unwrap().values
    );
    assert_eq!(r.points, s.points);
    assert_eq!(r.lights.len(), 3);
    for (a, b) in r.lights.iter().zip(&s.lights) {
        assert_eq!(a.path, b.path);
        assert_eq!(a.kind, b.kind);
        assert_eq!(a.color, b.color);
        assert_eq!(a.intensity, b.intensity);
        assert!((a.transform - b.transform).abs().max() < 1e-12);
    }
    assert_eq!(r.lights[0].path, "/Reference/XFormDomeLight/DomeLight");
    assert_eq!(
        r.lights[0].kind,
        LightKind::Dome {
            file: "garden.exr".into()
        }
    );
    let c = r.camera.unwrap();
    assert!((c.fov_deg - cam.fov_deg).abs() < 1e-9);
    assert_eq!(translation(&c.transform), cam.eye);
}

#[test]
fn lights_become_cgnodes_lights_with_the_framework_transforms() {
    let s = sample_stage();
    let mut asked = Vec::new();
    let mut load = |f: &str| {
        asked.push(f.to_string());
        Ok(None)
    };
    let mut warnings = Vec::new();
    let (scene, cam) = stage_to_scene(&s, 32, 24, &mut load, &mut warnings).unwrap();
    assert_eq!(asked, vec!["garden.exr".to_string()]);
    assert_eq!(warnings.len(), 1, "{warnings:?}"); // the missing texture
    match &scene.lights[0] {
        Light::Environment {
            image,
            color,
            rotation_deg,
            ..
        } => {
            assert!(image.is_none());
            assert_eq!(*color, [1.0, 1.0, 2.013]);
            // Rotate Z 30 degrees on a Z-up stage: a 30 degree turn about up.
            assert!((rotation_deg - 30.0).abs() < 1e-9, "{rotation_deg}");
        }
        l => panic!("{l:?}"),
    }
    // The Z-up stage is turned into cgnodes' Y-up world, (x, y, z) -> (x, z, -y): the point
    // light at (1, -2, 3.5) on the stage is at (1, 3.5, 2).
    assert_eq!(
        scene.lights[1],
        Light::Point {
            position: [1.0, 3.5, 2.0],
            color: [0.25, 0.5, 1.0],
            intensity: 2.0
        }
    );
    // Rotate X 90: local -Z (the light's direction) turns to +Y on the stage (x-rotation,
    // right-handed), which is -Z in the Y-up scene.
    match &scene.lights[2] {
        Light::Directional { direction, .. } => {
            let want = [0.0, 0.0, -1.0];
            assert!(
                (0..3).all(|k| (direction[k] - want[k]).abs() < 1e-12),
                "{direction:?}"
            );
        }
        l => panic!("{l:?}"),
    }
    // Two objects: the quad with its mean colour, the three particles as 3 octahedra.
    assert_eq!(scene.objects.len(), 2);
    let mat = scene.objects[0].material.as_ref().unwrap();
    assert_eq!(mat.base_color, [0.375, 0.375, 0.375]);
    let splats = &scene.objects[1].mesh;
    assert_eq!((splats.positions.len(), splats.num_faces()), (18, 24));
    // The third particle's octahedron reaches width/2 = 0.025 along +x from its centre.
    assert!((splats.positions[12][0] - (-1.0 + 0.025)).abs() < 1e-12);
    let tex = scene.objects[1]
        .material
        .as_ref()
        .unwrap()
        .base_color_texture
        .clone()
        .unwrap();
    assert_eq!((tex.width, tex.height), (2, 2));
    assert_eq!(tex.pixels[1], [0.9, 0.2, 0.1, 1.0]);
    assert_eq!(cam.width, 32);
    // the default camera's up (the stage's +Z) is the scene's +Y
    assert!(
        cam.up[1] > 0.99 && scene.camera.as_ref() == Some(&cam),
        "{:?}",
        cam.up
    );
}

#[test]
fn the_default_camera_sees_the_whole_box() {
    for up in [UpAxis::Y, UpAxis::Z] {
        let (lo, hi) = ([0.0, 0.0, 0.0], [1.2, 3.0, 2.0]);
        let cam = default_camera(lo, hi, up, 640, 480);
        cam.check().unwrap();
        let b = cam.look_at::<f64>();
        let f = cam.focal_length_px();
        for i in 0..8 {
            let p = [
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            ];
            let v = b.to_view(p);
            assert!(v[2] > cam.near);
            let (x, y) = (320.0 + f * v[0] / v[2], 240.0 - f * v[1] / v[2]);
            assert!(
                (0.0..640.0).contains(&x) && (0.0..480.0).contains(&y),
                "{up:?} {p:?} -> {x} {y}"
            );
        }
        // Up on the screen is up in the world.
        assert!(b.up[if up == UpAxis::Z { 2 } else { 1 }] > 0.5);
    }
}

#[test]
fn meshes_without_faces_are_read_as_points_and_bad_input_is_an_error() {
    let text = "#usda 1.0\n(\n    upAxis = \"Z\"\n)\ndef Mesh \"geometry\"\n{\n    int[] faceVertexCounts = []\n    int[] faceVertexIndices = []\n    point3f[] points = [(0, 0, 0), (1, 1, 1)]\n}\n";
    let s = read_stage(text).unwrap();
    assert_eq!((s.meshes.len(), s.points.len()), (0, 1));
    assert_eq!(s.points[0].points.len(), 2);
    assert!(s.points[0].widths[0] > 0.0);
    let bad = "#usda 1.0\ndef Points \"p\"\n{\n    point3f[] points = [(0, 0, 0)]\n    float[] widths = [1, 2]\n}\n";
    assert!(read_stage(bad).unwrap_err().to_string().contains("widths"));
    let bad_light = "#usda 1.0\ndef SphereLight \"l\"\n{\n    float inputs:intensity = -1\n}\n";
    assert!(read_stage(bad_light).is_err());
}
