use super::*;
use crate::plugin::npy::NpyArray;
use cgnodes_api::types::*;
use serde_json::json;
use std::path::Path;

use std::collections::BTreeMap;

fn tri() -> Mesh {
    Mesh::from_triangles(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        &[[0, 1, 2]],
    )
    .unwrap()
}

#[test]
fn meshes_round_trip_and_bad_outputs_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let j = encode(&Value::from(tri()), dir, "in.mesh").unwrap();
    // Every array the request names exists and has the documented shape.
    let tri_file = NpyArray::read(Path::new(j["triangles"].as_str().unwrap())).unwrap();
    assert_eq!(tri_file.shape, vec![1, 3]);
    let back = decode(&SocketType::Mesh, &j, dir, &BTreeMap::new()).unwrap();
    let Value::Mesh(m) = back else { panic!() };
    assert_eq!(m.positions, tri().positions);
    assert_eq!(m.face_indices(), [0, 1, 2]);

    let mut inputs = BTreeMap::new();
    inputs.insert("mesh".to_string(), Value::from(tri()));
    let write = |name: &str, a: NpyArray| a.write(&dir.join(name)).unwrap();
    write(
        "p.npy",
        NpyArray::from_f64(&[3, 3], &[0.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 1.0, 1.0]),
    );
    let m = decode(
        &SocketType::Mesh,
        &json!({"base": "mesh", "positions": "p.npy"}),
        dir,
        &inputs,
    )
    .unwrap();
    let Value::Mesh(m) = m else { panic!() };
    assert_eq!(m.positions[2], [0.0, 1.0, 1.0]);
    // An index past the last vertex.
    write("t.npy", NpyArray::from_i32(&[1, 3], &[0, 1, 3]));
    let e = decode(
        &SocketType::Mesh,
        &json!({"positions": "p.npy", "triangles": "t.npy"}),
        dir,
        &inputs,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("refers to vertex 3"), "{e}");
    // Float indices, a path out of the folder, a base that is not a mesh input.
    write("tf.npy", NpyArray::from_f64(&[1, 3], &[0.0, 1.0, 2.0]));
    let e = decode(
        &SocketType::Mesh,
        &json!({"positions": "p.npy", "triangles": "tf.npy"}),
        dir,
        &inputs,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("integer"), "{e}");
    let e = decode(
        &SocketType::Mesh,
        &json!({"base": "mesh", "positions": "../p.npy"}),
        dir,
        &inputs,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("leaves the call folder"), "{e}");
    let e = decode(
        &SocketType::Mesh,
        &json!({"base": "x", "positions": "p.npy"}),
        dir,
        &inputs,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("not a mesh input"), "{e}");
}

#[test]
fn images_accept_rgb_and_refuse_other_shapes() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    NpyArray::from_f64(&[1, 2, 3], &[0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
        .write(&dir.join("rgb.npy"))
        .unwrap();
    let v = decode(
        &SocketType::Image,
        &json!({"pixels": "rgb.npy"}),
        dir,
        &BTreeMap::new(),
    )
    .unwrap();
    let Value::Image(img) = v else { panic!() };
    assert_eq!((img.width, img.height), (2, 1));
    assert_eq!(img.pixels[1], [0.4, 0.5, 0.6, 1.0]);
    NpyArray::from_f64(&[2, 2], &[0.0; 4])
        .write(&dir.join("flat.npy"))
        .unwrap();
    let e = decode(
        &SocketType::Image,
        &json!({"pixels": "flat.npy"}),
        dir,
        &BTreeMap::new(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("(H, W, 4)"), "{e}");
}
