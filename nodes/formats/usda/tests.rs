use super::transform::{rotation, world_transform, Mat4};
use super::*;
use cgnodes_api::prelude::*;

const QUAD: &str = r#"#usda 1.0
(
    defaultPrim = "Root"
)

def Xform "Root"
{
    double3 xformOp:translate = (1, 2, 3)
    uniform token[] xformOpOrder = ["xformOp:translate"]

    def Mesh "Quad" (
        prepend apiSchemas = ["MaterialBindingAPI"]
    )
    {
        int[] faceVertexCounts = [4]
        int[] faceVertexIndices = [0, 1, 2, 3]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
        texCoord2f[] primvars:st = [(0, 0), (1, 1)] (
            interpolation = "faceVarying"
        )
        int[] primvars:st:indices = [0, 1, 1, 0]
        rel material:binding = </mat>
    }
}
"#;

#[test]
fn reads_translated_quad_with_indexed_uvs() {
    let m = read_usda(QUAD, "", true).unwrap();
    assert_eq!(m.positions[2], [2.0, 3.0, 3.0]);
    assert_eq!(m.face_counts(), &[4]);
    let uv = m.uvs.unwrap();
    assert_eq!(uv.domain, Domain::Corner);
    assert_eq!(
        uv.values,
        vec![[0.0, 0.0], [1.0, 1.0], [1.0, 1.0], [0.0, 0.0]]
    );
    let raw = read_usda(QUAD, "/Root/Quad", false).unwrap();
    assert_eq!(raw.positions[2], [1.0, 1.0, 0.0]);
}

#[test]
fn rotate_x_turns_y_into_z() {
    // USD rotateX by +90 degrees maps +Y to +Z (right-handed).
    let m = rotation(0, 90.0);
    let p = [0.0, 1.0, 0.0, 1.0];
    let z: f64 = (0..4).map(|k| p[k] * m[(k, 2)]).sum();
    assert!((z - 1.0).abs() < 1e-12);
}

#[test]
fn errors_name_the_line() {
    let bad = QUAD.replace("(1, 0, 0), (1, 1, 0)", "(1, 0, 0), (1, 1 0)");
    let e = read_usda(&bad, "", true).unwrap_err().to_string();
    assert!(e.starts_with("line 17:"), "{e}");
    let bad = QUAD.replace("[0, 1, 2, 3]", "[0, 1, 2, 7]");
    let e = read_usda(&bad, "", true).unwrap_err().to_string();
    assert!(e.contains("line 16") && e.contains("out of range"), "{e}");
    let bad = QUAD.replace("(0, 1, 0)]", "(0, nan, 0)]");
    let e = read_usda(&bad, "", true).unwrap_err().to_string();
    assert!(e.contains("line 17") && e.contains("finite"), "{e}");
    let bad = QUAD.replace("def Mesh", "def Mesh Mesh");
    assert!(read_usda(&bad, "", true)
        .unwrap_err()
        .to_string()
        .starts_with("line 11:"));
    let e = read_usda(QUAD, "/Root", true).unwrap_err().to_string();
    assert!(e.contains("not a Mesh"), "{e}");
    let bad = QUAD.replace("xformOp:translate\"]", "xformOp:shear\"]");
    let e = read_usda(&bad, "", true).unwrap_err().to_string();
    assert!(e.contains("line 9"), "{e}");
}

#[test]
fn write_then_read_is_exact() {
    let mut m = read_usda(QUAD, "", true).unwrap();
    m.positions[1][0] = 0.1 + 0.2; // not representable in f32
    let mut buf = Vec::new();
    write_usda(&m, "/a/b", &mut buf).unwrap();
    let text = String::from_utf8(buf).unwrap();
    let r = read_usda(&text, "/a/b", true).unwrap();
    assert_eq!(r.positions, m.positions);
    assert_eq!(r.face_indices(), m.face_indices());
    assert_eq!(r.uvs, m.uvs);
}

/// The explicit row-vector product the reader used before it moved to nalgebra, as a
/// reference: `c[i][j] = sum_k a[i][k] * b[k][j]`.
fn reference_matmul(a: &Mat4, b: &Mat4) -> Mat4 {
    Mat4::from_fn(|i, j| (0..4).map(|k| a[(i, k)] * b[(k, j)]).sum())
}

#[test]
fn nalgebra_products_match_the_explicit_sums_bit_for_bit() {
    let mut seed = 12345u64;
    let mut rnd = || {
        let x = cgnodes_api::rng::lcg_next(&mut seed);
        match seed % 7 {
            0 => 0.0,
            1 => -0.0,
            _ => (x - 0.5) * 10f64.powi((seed % 5) as i32 - 2),
        }
    };
    for _ in 0..200 {
        let a = Mat4::from_fn(|_, _| rnd());
        let b = Mat4::from_fn(|_, _| rnd());
        let c = a * b;
        let r = reference_matmul(&a, &b);
        for (x, y) in c.iter().zip(r.iter()) {
            assert_eq!(x.to_bits(), y.to_bits());
        }
        let v = nalgebra::RowVector4::new(rnd(), rnd(), rnd(), 1.0);
        let o = v * a;
        for j in 0..4 {
            let s: f64 = (0..4).map(|k| v[k] * a[(k, j)]).sum();
            assert_eq!(o[j].to_bits(), s.to_bits());
        }
    }
    // the rotateXYZ product and a chain compose like before
    let r = rotation(0, 30.0) * rotation(1, 45.0) * rotation(2, 60.0);
    let e = reference_matmul(
        &reference_matmul(&rotation(0, 30.0), &rotation(1, 45.0)),
        &rotation(2, 60.0),
    );
    assert_eq!(r, e);
    assert_eq!(world_transform(&[]).unwrap(), Mat4::identity());
}

/// Issue 23: ten thousand nested lists or prims overflowed the stack and aborted the process;
/// past `MAX_NESTING` levels they are an error naming the line.
#[test]
fn deep_nesting_is_an_error_not_a_stack_overflow() {
    let lists = format!(
        "#usda 1.0\ndef Mesh \"m\" {{\n    int[] a = {}1{}\n}}\n",
        "[".repeat(10_000),
        "]".repeat(10_000)
    );
    let e = parse_usda(&lists).unwrap_err().to_string();
    assert!(e.contains("nesting deeper than 200"), "{e}");
    let prims = format!(
        "#usda 1.0\n{}{}",
        "def Xform \"x\" {\n".repeat(10_000),
        "}\n".repeat(10_000)
    );
    let e = parse_usda(&prims).unwrap_err().to_string();
    assert!(e.starts_with("line 202:") && e.contains("nesting"), "{e}");
    // Nesting within the limit still parses.
    let ok = format!(
        "#usda 1.0\n{}{}",
        "def Xform \"x\" {\n".repeat(50),
        "}\n".repeat(50)
    );
    assert_eq!(parse_usda(&ok).unwrap().prims.len(), 1);
}

/// Issue 23: face counts are checked before their sum is trusted: huge counts whose i64 sum
/// overflowed (a panic in debug builds, a wrapped total otherwise), and integers a double
/// cannot hold exactly (1e300 became i64::MAX), are errors naming the line.
#[test]
fn hostile_face_counts_are_errors() {
    let many = vec!["9007199254740992"; 1100].join(", ");
    let bad = QUAD.replace(
        "faceVertexCounts = [4]",
        &format!("faceVertexCounts = [{many}]"),
    );
    let e = read_usda(&bad, "", true).unwrap_err().to_string();
    assert!(
        e.starts_with("line 16:")
            && e.contains("add up to more than the 4 entries of faceVertexIndices (at face 0"),
        "{e}"
    );
    let bad = QUAD.replace("faceVertexCounts = [4]", "faceVertexCounts = [1e300]");
    let e = read_usda(&bad, "", true).unwrap_err().to_string();
    assert!(
        e.starts_with("line 15:") && e.contains("beyond the exact integers"),
        "{e}"
    );
    let bad = QUAD.replace("faceVertexCounts = [4]", "faceVertexCounts = [3, 3]");
    let e = read_usda(&bad, "", true).unwrap_err().to_string();
    assert!(e.contains("at face 1, 3 corners"), "{e}");
    let bad = QUAD.replace("faceVertexCounts = [4]", "faceVertexCounts = [3]");
    let e = read_usda(&bad, "", true).unwrap_err().to_string();
    assert!(
        e.contains("add up to 3 but faceVertexIndices has 4 entries"),
        "{e}"
    );
}

#[test]
fn blender_custom_data_dictionaries_are_read() {
    // As in the course's arm_with_cloth.usda (Blender 4.1 export).
    let text = r#"#usda 1.0
def Xform "root" (
    customData = {
        dictionary Blender = {
            bool generated = 1
            string name = "x"
        }
    }
)
{
    def Mesh "M"
    {
        int[] faceVertexCounts = [3]
        int[] faceVertexIndices = [0, 1, 2]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    }
}
"#;
    let m = read_usda(text, "/root/M", true).unwrap();
    assert_eq!(m.positions[1], [1.0, 0.0, 0.0]);
    // A dictionary that does not close is still an error with its line.
    let bad = text.replace("string name = \"x\"", "string name = ");
    assert!(read_usda(&bad, "/root/M", true)
        .unwrap_err()
        .to_string()
        .contains("line"));
}
