//! Tests of the PLY reader and writer.

use super::*;

const SQUARE: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";

/// Issue 23: a binary element with no properties and a count near 2^64 looped without
/// reading a byte; a vertex coordinate declared as a list of length 0 indexed out of bounds.
#[test]
fn hostile_headers_are_errors() {
    let junk =
        "ply\nformat binary_little_endian 1.0\nelement junk 18446744073709551615\nend_header\n";
    let e = read_ply(junk.as_bytes()).unwrap_err().to_string();
    assert!(
        e.contains("element 'junk' declares 18446744073709551615 instances but no properties"),
        "{e}"
    );
    let empty_x = "ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar float x\nproperty float y\nproperty float z\nend_header\n0 1 2\n";
    let e = read_ply(empty_x.as_bytes()).unwrap_err().to_string();
    assert!(
        e.contains("vertex 0: x, y and z need one value each"),
        "{e}"
    );
}

#[test]
fn ascii_square_and_line_numbers() {
    let m = read_ply(SQUARE.as_bytes()).unwrap();
    assert_eq!(m.face(0), &[0, 1, 2, 3]);
    assert_eq!(m.positions[2], [1.0, 1.0, 0.0]);
    let e = read_ply(SQUARE.replace("1 1 0", "1 x 0").as_bytes())
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("line 12:"), "{e}");
}

#[test]
fn binary_round_trip_is_exact() {
    let mut m = read_ply(SQUARE.as_bytes()).unwrap();
    m.positions[1][1] = 0.1 + 0.2;
    m.uvs = Some(Attribute {
        domain: Domain::Corner,
        values: vec![[0.1, 0.2], [0.3, 0.4], [0.5, 0.6], [0.7, 0.8]],
    });
    for binary in [false, true] {
        let mut buf = Vec::new();
        write_ply(&m, binary, &mut buf).unwrap();
        let r = read_ply(&buf).unwrap();
        assert_eq!(r.positions, m.positions);
        assert_eq!(r.face_indices(), m.face_indices());
        assert_eq!(r.uvs, m.uvs);
    }
}

/// A `count`-corner polygon on the unit circle, with per-corner UVs.
fn big_polygon(count: usize) -> Mesh {
    let p: Vec<[f64; 3]> = (0..count)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / count as f64;
            [a.cos(), a.sin(), 0.0]
        })
        .collect();
    let mut m = Mesh::new(p, vec![count as u32], (0..count as u32).collect()).unwrap();
    m.uvs = Some(Attribute {
        domain: Domain::Corner,
        values: (0..count).map(|k| [k as f64, 0.5]).collect(),
    });
    m
}

/// Issue 23: the writer clamped list counts to 255 (a uchar) but wrote every index, so a
/// 300-corner face (and any face past 127 corners with per-corner UVs) corrupted the file.
/// The count type now widens with the largest face; small faces keep `uchar`.
#[test]
fn faces_past_255_corners_round_trip() {
    for (count, idx_ty, uv_ty) in [
        (300, "ushort", "ushort"),
        (200, "uchar", "ushort"),
        (70_000, "uint", "uint"),
    ] {
        let m = big_polygon(count);
        for binary in [false, true] {
            let mut buf = Vec::new();
            write_ply(&m, binary, &mut buf).unwrap();
            let end = buf.windows(10).position(|w| w == b"end_header").unwrap();
            let head = String::from_utf8_lossy(&buf[..end]).to_string();
            assert!(
                head.contains(&format!("property list {idx_ty} int vertex_indices")),
                "{head}"
            );
            assert!(
                head.contains(&format!("property list {uv_ty} double texcoord")),
                "{head}"
            );
            let r = read_ply(&buf).unwrap();
            assert_eq!(r.face_counts(), &[count as u32]);
            assert_eq!(r.face_indices(), m.face_indices());
            assert_eq!(r.positions, m.positions);
            assert_eq!(r.uvs, m.uvs);
        }
    }
    let mut buf = Vec::new();
    write_ply(&read_ply(SQUARE.as_bytes()).unwrap(), true, &mut buf).unwrap();
    assert!(String::from_utf8_lossy(&buf).contains("property list uchar int vertex_indices"));
}

/// The reader takes every integer list count type.
#[test]
fn list_counts_of_every_integer_type() {
    for ty in [
        "char", "uchar", "short", "ushort", "int", "uint", "int8", "uint16", "int32", "uint32",
    ] {
        let t = SQUARE.replace("list uchar int", &format!("list {ty} int"));
        assert_eq!(
            read_ply(t.as_bytes()).unwrap().face(0),
            &[0, 1, 2, 3],
            "{ty}"
        );
    }
    // Binary, a uint count.
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n".to_vec();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b.extend_from_slice(&3u32.to_le_bytes());
    for i in [0i32, 1, 2] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    assert_eq!(read_ply(&b).unwrap().face(0), &[0, 1, 2]);
}

/// Issue 23: declared element counts are checked against the bytes of the body before
/// anything is read (a 100-byte file cannot hold 10^12 vertices), in ASCII and binary, and
/// overflowing products count as too large.
#[test]
fn element_counts_beyond_the_file_are_refused() {
    let huge = SQUARE.replace("element vertex 4", "element vertex 1000000000000");
    let e = read_ply(huge.as_bytes()).unwrap_err().to_string();
    assert!(
        e.contains("element 'vertex' declares 1000000000000 instances, more than the"),
        "{e}"
    );
    // Exactly enough bytes in ASCII: "0 0 0\n" per vertex is 6 bytes, the minimum.
    let tight = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 1 1";
    assert_eq!(read_ply(tight.as_bytes()).unwrap().num_vertices(), 2);
    let short = tight.replace("vertex 2", "vertex 3");
    assert!(read_ply(short.as_bytes())
        .unwrap_err()
        .to_string()
        .contains("more than the 11 bytes"));
    // Binary: 12 bytes per float vertex; a face element with 2^64 - 1 instances overflows.
    let mut b = b"ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement face 18446744073709551615\nproperty list uint int vertex_indices\nend_header\n".to_vec();
    b.extend_from_slice(&[0; 12]);
    let e = read_ply(&b).unwrap_err().to_string();
    assert!(
        e.contains("element 'face' declares 18446744073709551615 instances"),
        "{e}"
    );
    let e = read_ply(&b[..b.len() - 1]).unwrap_err().to_string();
    assert!(
        e.contains("element 'vertex' declares 1 instances, more than the 11 bytes"),
        "{e}"
    );
}

/// Face indices must be whole numbers: NaN became vertex 0 and 1.5 became 1 through
/// `as usize`. A repeated corner is found in a large face too.
#[test]
fn fractional_or_nan_indices_and_large_repeats_are_errors() {
    for bad in ["nan", "1.5", "-0.5", "inf"] {
        let t = SQUARE.replace("4 0 1 2 3", &format!("4 0 {bad} 2 3"));
        let e = read_ply(t.as_bytes()).unwrap_err().to_string();
        assert!(e.contains("face 0 refers to vertex"), "{bad}: {e}");
    }
    let n = 5000;
    let mut t = format!("ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n");
    for k in 0..n {
        t.push_str(&format!("{k} {} 0\n", k * k));
    }
    let mut idx: Vec<usize> = (0..n).collect();
    idx[n - 1] = 17;
    t.push_str(&format!(
        "{n} {}\n",
        idx.iter()
            .map(|i| i.to_string())
            .collect::<Vec<_>>()
            .join(" ")
    ));
    let e = read_ply(t.as_bytes()).unwrap_err().to_string();
    assert!(
        e.contains("face 0 is degenerate: vertex 17 appears twice"),
        "{e}"
    );
}
