//! The bad-input corpus (issue 23, docs/reliability.md): hostile files and graphs for every
//! reader and many node types, each run through the `cgnodes` binary as a user would. Every
//! case must end with its documented exit code and an error that names what went wrong, and
//! none may panic, hang or leave a temporary file behind. Crashing inputs found by the fuzz
//! targets (`fuzz/`) are kept here as cases too.
//!
//! `CGNODES_HOSTILE_REPORT=FILE` writes the table of docs/reliability.md (case, exit code,
//! time, first error line) to FILE.

use crate::common::root;
use std::fmt::Write as _;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// A case is killed (and fails) after this long: far above the 2 s every case must meet, so
/// a loaded CI machine does not make it flaky; the report lists the real times.
const HANG: Duration = Duration::from_secs(20);

/// One hostile input: files written to a fresh folder, the command run there, and what the
/// user must get.
struct Case {
    name: &'static str,
    /// The reader or node family the case attacks (groups the report).
    reader: &'static str,
    files: Vec<(&'static str, Vec<u8>)>,
    /// Arguments after `cgnodes`; `graph.json` and `out` are in the case folder.
    args: Vec<String>,
    exit: i32,
    /// Substrings the combined stdout and stderr must contain.
    expect: Vec<&'static str>,
}

fn args(a: &[&str]) -> Vec<String> {
    a.iter().map(|s| s.to_string()).collect()
}

fn run_args() -> Vec<String> {
    args(&["run", "graph.json", "--out", "out"])
}

/// A graph of `nodes` (the JSON object's body) whose outputs feed `print` nodes.
fn graph(nodes: &str) -> Vec<u8> {
    format!(r#"{{"format": "cgnodes-graph", "version": 1, "nodes": {{{nodes}}}}}"#).into_bytes()
}

/// `mesh_load` of `file`, printed.
fn load_graph(file: &str) -> Vec<u8> {
    graph(&format!(
        r#""m": {{"type": "mesh_load", "params": {{"path": "{file}"}}}},
           "p": {{"type": "print", "inputs": {{"value": "m.mesh"}}}}"#
    ))
}

/// A mesh file attacked through `mesh_load`: exit 1, the node and the file named.
fn mesh_case(
    name: &'static str,
    reader: &'static str,
    file: &'static str,
    bytes: Vec<u8>,
    expect: &'static str,
) -> Case {
    Case {
        name,
        reader,
        files: vec![(file, bytes), ("graph.json", load_graph(file))],
        args: run_args(),
        exit: 1,
        expect: vec!["'m' (mesh_load)", file, expect],
    }
}

/// A graph that must be refused before anything runs: exit 3.
fn graph_case(name: &'static str, text: &str, expect: Vec<&'static str>) -> Case {
    Case {
        name,
        reader: "graph",
        files: vec![("graph.json", text.as_bytes().to_vec())],
        args: run_args(),
        exit: 3,
        expect,
    }
}

/// A node given hostile parameters: the node fails (exit 1) or the graph is refused (exit 3).
fn node_case(name: &'static str, nodes: &str, exit: i32, expect: Vec<&'static str>) -> Case {
    Case {
        name,
        reader: "node",
        files: vec![("graph.json", graph(nodes))],
        args: run_args(),
        exit,
        expect,
    }
}

fn ply_header(format: &str, body: &str) -> Vec<u8> {
    format!("ply\nformat {format} 1.0\n{body}end_header\n").into_bytes()
}

fn tri_ply_binary() -> Vec<u8> {
    let mut b = ply_header(
        "binary_little_endian",
        "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
         element face 1\nproperty list uchar int vertex_indices\n",
    );
    for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b.push(3);
    for i in [0i32, 1, 2] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    b
}

/// A PNG signature and IHDR chunk declaring `w` x `h` RGBA pixels, with no image data.
fn png_header(w: u32, h: u32) -> Vec<u8> {
    let mut b = vec![0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 6, 0, 0, 0]);
    b.extend_from_slice(&13u32.to_be_bytes());
    b.extend_from_slice(&ihdr);
    b.extend_from_slice(&crc32(&ihdr).to_be_bytes());
    b
}

/// A 64 x 64 test image encoded in the format of extension `ext` by the image crate.
fn encoded(ext: &str) -> Vec<u8> {
    let img = image::Rgb32FImage::from_fn(64, 64, |x, y| {
        image::Rgb([x as f32 / 64.0, y as f32 / 64.0, ((x ^ y) & 7) as f32 / 8.0])
    });
    let img = image::DynamicImage::ImageRgb32F(img);
    let img = match ext {
        "exr" | "hdr" => img,
        _ => image::DynamicImage::ImageRgb8(img.to_rgb8()),
    };
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::from_extension(ext).unwrap())
        .unwrap();
    out.into_inner()
}

/// The first half of `b`.
fn half(mut b: Vec<u8>) -> Vec<u8> {
    b.truncate(b.len() / 2);
    b
}

/// `b` with one bit flipped in its middle.
fn flipped(mut b: Vec<u8>) -> Vec<u8> {
    let i = b.len() / 2;
    b[i] ^= 0x10;
    b
}

/// CRC-32 of PNG chunks (ISO 3309, as the PNG specification's annex D gives it).
fn crc32(data: &[u8]) -> u32 {
    let mut c = 0xffff_ffffu32;
    for &b in data {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xedb8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// An OBJ of one convex face with `n` corners on the unit circle (ear clipping was O(n³)).
fn big_polygon_obj(n: usize) -> Vec<u8> {
    let mut t = String::new();
    for k in 0..n {
        let a = std::f64::consts::TAU * k as f64 / n as f64;
        t.push_str(&format!("v {} {} 0\n", a.cos(), a.sin()));
    }
    t.push('f');
    for k in 1..=n {
        t.push_str(&format!(" {k}"));
    }
    t.push('\n');
    t.into_bytes()
}

fn nested(open: &str, close: &str, n: usize) -> String {
    format!("{}{}", open.repeat(n), close.repeat(n))
}

/// Native graph files that must be refused with exit 3 (or, for output paths, whose writing
/// node fails with exit 1 before it writes anything).
fn graph_cases() -> Vec<Case> {
    let g = |nodes: &str| String::from_utf8(graph(nodes)).unwrap();
    let write_case = |name, text: &str, expect| Case {
        exit: 1,
        ..graph_case(name, text, expect)
    };
    vec![
        graph_case(
            "malformed JSON",
            r#"{"format": "cgnodes-graph", "nodes": {"#,
            vec!["graph.json:1:", "EOF"],
        ),
        graph_case("empty file", "", vec!["graph.json"]),
        graph_case("not an object", "[1, 2, 3]", vec!["graph.json"]),
        graph_case(
            "no format",
            r#"{"nodes": {}}"#,
            vec!["graph.json", "format"],
        ),
        graph_case(
            "future version",
            r#"{"format": "cgnodes-graph", "version": 99, "nodes": {}}"#,
            vec!["graph.json", "99"],
        ),
        graph_case(
            "unknown node type",
            &g(r#""x": {"type": "no_such_node"}"#),
            vec!["'x'", "no_such_node"],
        ),
        graph_case(
            "unknown input socket",
            &g(r#""x": {"type": "value_float", "params": {"valeu": 1.0}},
                 "p": {"type": "print", "inputs": {"value": "x.value"}}"#),
            vec!["'x'", "value_float", "valeu"],
        ),
        graph_case(
            "type mismatch on a link",
            &g(r#""s": {"type": "value_string", "params": {"value": "a"}},
                 "m": {"type": "mesh_grid", "inputs": {"cells_u": "s.value"}},
                 "p": {"type": "print", "inputs": {"value": "m.mesh"}}"#),
            vec!["'m'", "mesh_grid", "cells_u", "string"],
        ),
        graph_case(
            "wrong literal type",
            &g(r#""m": {"type": "mesh_grid", "params": {"cells_u": "ten"}},
                 "p": {"type": "print", "inputs": {"value": "m.mesh"}}"#),
            vec!["'m'", "mesh_grid", "cells_u"],
        ),
        graph_case(
            "cycle",
            &g(
                r#""a": {"type": "mesh_triangulate", "inputs": {"mesh": "b.mesh"}},
                 "b": {"type": "mesh_triangulate", "inputs": {"mesh": "a.mesh"}},
                 "p": {"type": "print", "inputs": {"value": "a.mesh"}}"#,
            ),
            vec!["cycle"],
        ),
        graph_case(
            "self link",
            &g(
                r#""a": {"type": "mesh_triangulate", "inputs": {"mesh": "a.mesh"}},
                 "p": {"type": "print", "inputs": {"value": "a.mesh"}}"#,
            ),
            vec!["cycle", "a -> a"],
        ),
        graph_case(
            "dangling link",
            &g(r#""p": {"type": "print", "inputs": {"value": "ghost.mesh"}}"#),
            vec!["'p'", "ghost"],
        ),
        graph_case(
            "link to an unknown output",
            &g(r#""m": {"type": "mesh_grid"},
                 "p": {"type": "print", "inputs": {"value": "m.meshh"}}"#),
            vec!["'m' (mesh_grid)", "meshh", "did you mean 'mesh'"],
        ),
        graph_case(
            "malformed link",
            &g(r#""p": {"type": "print", "inputs": {"value": "no-dot-here"}}"#),
            vec!["'p'", "no-dot-here"],
        ),
        graph_case(
            "missing required input",
            &g(r#""t": {"type": "tutte"}, "p": {"type": "print", "inputs": {"value": "t.mesh"}}"#),
            vec!["'t'", "tutte", "mesh"],
        ),
        graph_case(
            "literal out of range",
            &g(r#""m": {"type": "mesh_grid", "params": {"cells_u": 0}},
                 "p": {"type": "print", "inputs": {"value": "m.mesh"}}"#),
            vec!["'m' (mesh_grid)", "cells_u", "below the minimum 1"],
        ),
        graph_case(
            "literal integer overflow",
            &g(r#""m": {"type": "mesh_grid", "params": {"cells_u": 1e300}},
                 "p": {"type": "print", "inputs": {"value": "m.mesh"}}"#),
            vec!["'m'", "cells_u"],
        ),
        graph_case(
            "unknown choice",
            &g(r#""m": {"type": "mesh_grid", "params": {"plane": "xw"}},
                 "p": {"type": "print", "inputs": {"value": "m.mesh"}}"#),
            vec!["'m'", "mesh_grid", "plane", "xw"],
        ),
        graph_case(
            "missing input file",
            &g(
                r#""m": {"type": "mesh_load", "params": {"path": "no_such.obj"}},
                 "p": {"type": "print", "inputs": {"value": "m.mesh"}}"#,
            ),
            vec!["'m'", "mesh_load", "path", "no_such.obj"],
        ),
        write_case(
            "output path escapes the output folder",
            &g(r#""m": {"type": "mesh_grid"},
                 "s": {"type": "mesh_save", "params": {"path": "../escaped.obj"}, "inputs": {"mesh": "m.mesh"}}"#),
            vec!["'s' (mesh_save)", "path", "leaves the output directory"],
        ),
        write_case(
            "absolute output path",
            &g(r#""m": {"type": "mesh_grid"},
                 "s": {"type": "mesh_save", "params": {"path": "/tmp/cgnodes_hostile.obj"}, "inputs": {"mesh": "m.mesh"}}"#),
            vec!["'s' (mesh_save)", "path", "is absolute"],
        ),
        write_case(
            "frame field too wide",
            &g(r#""m": {"type": "mesh_grid"},
                 "s": {"type": "mesh_save", "params": {"path": "m_{frame:070000}.obj"}, "inputs": {"mesh": "m.mesh"}}"#),
            vec!["'s' (mesh_save)", "path", "at most 20 digits"],
        ),
        graph_case(
            "10k nested arrays",
            &format!(
                r#"{{"format": "cgnodes-graph", "version": 1, "nodes": {{}}, "meta": {}}}"#,
                nested("[", "]", 10_000)
            ),
            vec!["graph.json", "recursion"],
        ),
        graph_case(
            "a graph naming a program",
            &g(r#""x": {"type": "exec", "params": {"command": "rm -rf /"}}"#),
            vec!["'x'", "exec"],
        ),
        graph_case("not UTF-8", "\u{0}", vec!["graph.json"]),
        graph_case(
            "the same node id twice",
            "{\"format\": \"cgnodes-graph\", \"version\": 1, \"nodes\": {\n\"a\": {\"type\": \"value_float\"},\n\"a\": {\"type\": \"value_int\"}\n}}",
            vec!["graph.json:3:", "duplicate key 'a'"],
        ),
        graph_case(
            "the same param twice",
            &g(r#""a": {"type": "value_float", "params": {"value": 1, "value": 2}},
                  "p": {"type": "print", "inputs": {"value": "a.value"}}"#),
            vec!["graph.json", "duplicate key 'value'"],
        ),
        graph_case(
            "two nodes in a cycle and nothing that writes",
            &g(r#""a": {"type": "math", "inputs": {"a": "b.value"}},
                  "b": {"type": "math", "inputs": {"a": "a.value"}}"#),
            vec!["nothing to run"],
        ),
        Case {
            args: args(&["validate", "graph.json"]),
            ..graph_case(
                "validate: a cycle no output needs",
                &g(r#""a": {"type": "math", "inputs": {"a": "b.value"}},
                      "b": {"type": "math", "inputs": {"a": "a.value"}}"#),
                vec!["graph.json", "cycle"],
            )
        },
        graph_case(
            "nothing writes, prints or is a target",
            &g(r#""a": {"type": "value_float"}"#),
            vec!["nothing to run: no node writes a file; name a --target"],
        ),
    ]
}

/// The course's Tutte blueprint (tests/data/f3d) with the socket its first link starts at
/// removed from `sockets_info` (this panicked while loading, before issue 23).
fn f3d_without_a_linked_socket() -> String {
    let text =
        std::fs::read_to_string(root().join("tests/data/f3d/hw4_tutte_blueprint.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let links = v["links_info"].as_object().unwrap();
    let start = links
        .values()
        .find_map(|l| l["StartPinID"].as_i64())
        .unwrap();
    let sockets = v["sockets_info"].as_object_mut().unwrap();
    let key = sockets
        .iter()
        .find(|(k, s)| s["ID"].as_i64() == Some(start) || k.parse::<i64>().ok() == Some(start))
        .map(|(k, _)| k.clone())
        .unwrap();
    sockets.remove(&key);
    v.to_string()
}

/// Framework3D node trees.
fn f3d_cases() -> Vec<Case> {
    let aliases = root().join("graphs/f3d/hw4_tutte_aliases.json");
    let case = |name: &'static str, text: &str, expect: Vec<&'static str>| Case {
        name,
        reader: "f3d",
        files: vec![("graph.json", text.as_bytes().to_vec())],
        args: vec![
            "run".into(),
            "graph.json".into(),
            "--out".into(),
            "out".into(),
            "--f3d-aliases".into(),
            aliases.display().to_string(),
        ],
        exit: 3,
        expect,
    };
    vec![
        case(
            "link to a socket missing from sockets_info",
            &f3d_without_a_linked_socket(),
            vec!["which sockets_info does not list"],
        ),
        case(
            "unknown Framework3D node",
            r#"{"nodes_info": {"1": {"ID": 1, "id_name": "hw99_magic", "inputs": [], "outputs": []}},
                "sockets_info": {}, "links_info": []}"#,
            vec!["hw99_magic"],
        ),
        case(
            "nodes_info of the wrong shape",
            r#"{"nodes_info": [1, 2, 3], "sockets_info": {}, "links_info": []}"#,
            vec!["graph.json"],
        ),
        case(
            "link between unknown sockets",
            r#"{"nodes_info": {}, "sockets_info": {},
                "links_info": [{"ID": 5, "StartPinID": 1, "EndPinID": 2}]}"#,
            vec!["graph.json"],
        ),
    ]
}

/// Mesh files through `mesh_load`.
fn mesh_cases() -> Vec<Case> {
    let t = |s: &str| s.as_bytes().to_vec();
    let mut v = vec![
        mesh_case("OBJ face index out of range", "obj", "in.obj", t("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"), "out of range"),
        mesh_case("OBJ face index 0", "obj", "in.obj", t("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"), "line 4"),
        mesh_case("OBJ NaN coordinate", "obj", "in.obj", t("v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), "line 1"),
        mesh_case("OBJ infinite coordinate", "obj", "in.obj", t("v inf 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), "line 1"),
        mesh_case("OBJ without faces", "obj", "in.obj", t("v 0 0 0\n"), "no faces"),
        mesh_case("OBJ empty file", "obj", "in.obj", Vec::new(), "no faces"),
        mesh_case("OBJ binary garbage", "obj", "in.obj", (0..=255u8).cycle().take(4096).collect(), "in.obj"),
        mesh_case("OBJ two-corner face", "obj", "in.obj", t("v 0 0 0\nv 1 0 0\nf 1 2\n"), "line 3"),
        mesh_case("OBJ cut inside its last vertex", "obj", "in.obj", t("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nv 1 1"), "line 5"),
        mesh_case("USDA cut in half", "usda", "in.usda", t("#usda 1.0\ndef Mesh \"m\" {\n    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1"), "in.usda"),
        Case {
            files: vec![
                ("in.obj", t("v 0 0 0\nv 1 0 0\nv 0 1 0\ng a\nf 1 2 3\n")),
                (
                    "graph.json",
                    graph(
                        r#""m": {"type": "mesh_load", "params": {"path": "in.obj", "group": "b"}},
                           "p": {"type": "print", "inputs": {"value": "m.mesh"}}"#,
                    ),
                ),
            ],
            ..mesh_case("OBJ unknown group", "obj", "in.obj", Vec::new(), "'b'")
        },
        mesh_case("OFF counts larger than the file", "off", "in.off", t("OFF\n100000000000 0 0"), "in.off"),
        mesh_case("OFF face count overflows", "off", "in.off", t("OFF\n3 6148914691236517206 0\n0 0 0\n1 0 0\n0 1 0\n"), "in.off"),
        mesh_case("OFF negative count", "off", "in.off", t("OFF\n-3 1 0\n"), "in.off"),
        mesh_case("OFF truncated", "off", "in.off", t("OFF\n3 1 0\n0 0 0\n1 0 0\n"), "in.off"),
        mesh_case("OFF face index out of range", "off", "in.off", t("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"), "in.off"),
        mesh_case("OFF huge face corner count", "off", "in.off", t("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n"), "in.off"),
        mesh_case(
            "PLY element of 2^64-1 rows without properties",
            "ply",
            "in.ply",
            ply_header("binary_little_endian", "element junk 18446744073709551615\n"),
            "junk",
        ),
        mesh_case(
            "PLY coordinate declared as a list",
            "ply",
            "in.ply",
            [ply_header("ascii", "element vertex 1\nproperty list uchar float x\n"), b"0\n".to_vec()].concat(),
            "in.ply",
        ),
        mesh_case(
            "PLY vertex count larger than the file",
            "ply",
            "in.ply",
            ply_header(
                "binary_little_endian",
                "element vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\n",
            ),
            "in.ply",
        ),
        mesh_case(
            "PLY ASCII vertex count larger than the file",
            "ply",
            "in.ply",
            ply_header("ascii", "element vertex 999999999999\nproperty float x\nproperty float y\nproperty float z\n"),
            "in.ply",
        ),
        mesh_case("PLY truncated binary body", "ply", "in.ply", tri_ply_binary()[..120].to_vec(), "in.ply"),
        mesh_case(
            "PLY unknown format",
            "ply",
            "in.ply",
            ply_header("binary_middle_endian", "element vertex 0\n"),
            "in.ply",
        ),
        mesh_case(
            "PLY face index out of range",
            "ply",
            "in.ply",
            [
                ply_header(
                    "ascii",
                    "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                     element face 1\nproperty list uchar int vertex_indices\n",
                ),
                b"0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n".to_vec(),
            ]
            .concat(),
            "in.ply",
        ),
        mesh_case(
            "PLY face list of 4 billion corners",
            "ply",
            "in.ply",
            {
                let mut b = tri_ply_binary();
                let n = b.len();
                b.truncate(n - 13);
                b.extend_from_slice(&[0xff]);
                b
            },
            "in.ply",
        ),
        mesh_case("PLY missing header end", "ply", "in.ply", b"ply\nformat ascii 1.0\nelement vertex 1\n".to_vec(), "in.ply"),
        mesh_case("USDA 10k nested brackets", "usda", "in.usda", t(&format!("#usda 1.0\ndef Mesh \"m\" {{ int[] x = {} }}\n", nested("[", "]", 10_000))), "nest"),
        mesh_case(
            "USDA 10k nested prims",
            "usda",
            "in.usda",
            t(&format!("#usda 1.0\n{}\n", nested("def Xform \"a\" {\n", "}\n", 10_000))),
            "nest",
        ),
        mesh_case(
            "USDA counts do not match indices",
            "usda",
            "in.usda",
            t("#usda 1.0\ndef Mesh \"m\" {\n point3f[] points = [(0,0,0),(1,0,0),(0,1,0)]\n int[] faceVertexCounts = [3, 3]\n int[] faceVertexIndices = [0, 1, 2]\n}\n"),
            "in.usda",
        ),
        mesh_case(
            "USDA negative face count",
            "usda",
            "in.usda",
            t("#usda 1.0\ndef Mesh \"m\" {\n point3f[] points = [(0,0,0),(1,0,0),(0,1,0)]\n int[] faceVertexCounts = [-3]\n int[] faceVertexIndices = [0, 1, 2]\n}\n"),
            "in.usda",
        ),
        mesh_case(
            "USDA index out of range",
            "usda",
            "in.usda",
            t("#usda 1.0\ndef Mesh \"m\" {\n point3f[] points = [(0,0,0),(1,0,0),(0,1,0)]\n int[] faceVertexCounts = [3]\n int[] faceVertexIndices = [0, 1, 99]\n}\n"),
            "in.usda",
        ),
        mesh_case(
            "USDA count sum overflows",
            "usda",
            "in.usda",
            t("#usda 1.0\ndef Mesh \"m\" {\n point3f[] points = [(0,0,0),(1,0,0),(0,1,0)]\n int[] faceVertexCounts = [9223372036854775807, 9223372036854775807]\n int[] faceVertexIndices = [0, 1, 2]\n}\n"),
            "in.usda",
        ),
        mesh_case("USDA unterminated string", "usda", "in.usda", t("#usda 1.0\ndef Mesh \"m {\n"), "in.usda"),
        mesh_case("USDA no mesh", "usda", "in.usda", t("#usda 1.0\ndef Xform \"x\" {\n}\n"), "in.usda"),
        Case {
            exit: 0,
            expect: vec!["99998 faces"],
            files: vec![
                ("in.obj", big_polygon_obj(100_000)),
                (
                    "graph.json",
                    graph(
                        r#""m": {"type": "mesh_load", "params": {"path": "in.obj"}},
                           "t": {"type": "mesh_triangulate", "inputs": {"mesh": "m.mesh"}},
                           "p": {"type": "print", "inputs": {"value": "t.mesh"}}"#,
                    ),
                ),
            ],
            ..mesh_case("one face of 100k corners, triangulated", "obj", "in.obj", Vec::new(), "")
        },
        mesh_case("unknown mesh extension", "mesh", "in.stl", t("solid x\nendsolid x\n"), "stl"),
    ];
    // An MTL that names a texture that is not there: the mesh still loads (materials are for
    // scenes), so this one exits 0.
    // Found by the mtl fuzz target: tobj panicked on a colour with fewer than three numbers.
    v.push(Case {
        name: "MTL colour with two numbers (mesh still loads)",
        reader: "mtl",
        files: vec![
            (
                "in.obj",
                t("mtllib in.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n"),
            ),
            ("in.mtl", t("newmtl a\nKs 0.95 0.5\n")),
            ("graph.json", load_graph("in.obj")),
        ],
        args: run_args(),
        exit: 0,
        expect: vec!["3 vertices, 1 faces"],
    });
    v.push(Case {
        name: "MTL naming a missing texture (mesh still loads)",
        reader: "mtl",
        files: vec![
            (
                "in.obj",
                t("mtllib in.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n"),
            ),
            (
                "in.mtl",
                t("newmtl a\nmap_Kd ../../../../etc/shadow\nKd nan nan nan\n"),
            ),
            ("graph.json", load_graph("in.obj")),
        ],
        args: run_args(),
        exit: 0,
        expect: vec![],
    });
    v
}

/// Images, tables and other files read by nodes.
fn file_cases() -> Vec<Case> {
    let image =
        |name: &'static str, file: &'static str, bytes: Vec<u8>, expect: &'static str| Case {
            name,
            reader: "image",
            files: vec![
                (file, bytes),
                (
                    "graph.json",
                    graph(&format!(
                        r#""i": {{"type": "image_load", "params": {{"path": "{file}"}}}},
                       "p": {{"type": "print", "inputs": {{"value": "i.image"}}}}"#
                    )),
                ),
            ],
            args: run_args(),
            exit: 1,
            expect: vec!["'i' (image_load)", file, expect],
        };
    let series = |name: &'static str, csv: &str, expect: Vec<&'static str>| Case {
        name,
        reader: "csv",
        files: vec![
            ("ref.csv", csv.as_bytes().to_vec()),
            (
                "graph.json",
                graph(
                    r#""t": {"type": "value_float", "params": {"value": 1.0}},
                       "c": {"type": "compare_series", "params": {"reference": "ref.csv", "x_column": "T", "y_column": "Z"}, "inputs": {"series": "t.value"}},
                       "p": {"type": "print", "inputs": {"value": "c.error"}}"#,
                ),
            ),
        ],
        args: run_args(),
        exit: 3,
        expect,
    };
    let mut v = vec![
        image(
            "PNG that is only a signature",
            "in.png",
            png_header(16, 16)[..8].to_vec(),
            "in.png",
        ),
        image(
            "PNG declaring 100000 x 100000 pixels",
            "in.png",
            png_header(100_000, 100_000),
            "in.png",
        ),
        image(
            "JPEG truncated after its header",
            "in.jpg",
            vec![0xff, 0xd8, 0xff, 0xe0, 0x00, 0x10, b'J', b'F'],
            "in.jpg",
        ),
        image("text named .png", "in.png", b"hello".to_vec(), "in.png"),
        image(
            "PNG cut after 120 bytes",
            "in.png",
            encoded("png")[..120].to_vec(),
            "truncated PNG",
        ),
        image(
            "PNG with a flipped byte in its pixel data",
            "in.png",
            flipped(encoded("png")),
            "CRC",
        ),
        image(
            "JPEG cut inside its scan",
            "in.jpg",
            half(encoded("jpg")),
            "truncated JPEG",
        ),
        image(
            "GIF without its trailer",
            "in.gif",
            {
                let mut b = encoded("gif");
                b.pop();
                b
            },
            "truncated GIF",
        ),
        image(
            "BMP cut inside its pixels",
            "in.bmp",
            half(encoded("bmp")),
            "truncated BMP",
        ),
        image("EXR cut in half", "in.exr", half(encoded("exr")), "in.exr"),
        image("HDR cut in half", "in.hdr", half(encoded("hdr")), "in.hdr"),
        image(
            "unknown image extension",
            "in.tga2",
            b"hello".to_vec(),
            "in.tga2",
        ),
    ];
    v.push(Case {
        name: "CSV cut inside its last row",
        reader: "csv",
        files: vec![
            ("in.csv", b"x,y\n0,1\n1,2\n2".to_vec()),
            (
                "graph.json",
                graph(
                    r#""t": {"type": "table_load", "params": {"path": "in.csv"}},
                       "p": {"type": "print", "inputs": {"value": "t.table"}}"#,
                ),
            ),
        ],
        args: run_args(),
        exit: 1,
        expect: vec!["'t' (table_load)", "in.csv", "truncated CSV"],
    });
    // compare_series takes a table; a float link is refused by type before any file is read.
    v.push(series(
        "compare_series fed a float",
        "T,Z\n0,1\n",
        vec!["'c'", "compare_series", "series"],
    ));
    v
}

/// Node parameters a graph can set or link to hostile values.
fn node_cases() -> Vec<Case> {
    vec![
        node_case(
            "linked dimension 4 into sph_fluid",
            r#""d": {"type": "value_int", "params": {"value": 4}},
               "f": {"type": "sph_fluid", "inputs": {"dimension": "d.value"}},
               "p": {"type": "print", "inputs": {"value": "f.points"}}"#,
            1,
            vec!["'f' (sph_fluid)", "dimension", "above the maximum 3"],
        ),
        node_case(
            "linked negative image_width into sph_fluid",
            r#""w": {"type": "value_int", "params": {"value": -5}},
               "f": {"type": "sph_fluid", "inputs": {"image_width": "w.value"}},
               "p": {"type": "print", "inputs": {"value": "f.image"}}"#,
            1,
            vec!["'f' (sph_fluid)", "image_width"],
        ),
        node_case(
            "linked huge grid",
            r#""n": {"type": "value_int", "params": {"value": 4000000000}},
               "m": {"type": "mesh_grid", "inputs": {"cells_u": "n.value", "cells_v": "n.value"}},
               "p": {"type": "print", "inputs": {"value": "m.mesh"}}"#,
            1,
            vec!["'m' (mesh_grid)", "cells_u"],
        ),
        node_case(
            "linked misspelt choice",
            r#""s": {"type": "value_string", "params": {"value": "semi-implicit"}},
               "g": {"type": "mesh_grid"},
               "c": {"type": "mass_spring", "inputs": {"mesh": "g.mesh", "integrator": "s.value"}},
               "p": {"type": "print", "inputs": {"value": "c.mesh"}}"#,
            1,
            vec!["'c' (mass_spring)", "integrator", "semi-implicit"],
        ),
        node_case(
            "linked misspelt camera fov_axis",
            r#""s": {"type": "value_string", "params": {"value": "diagonal"}},
               "c": {"type": "camera", "inputs": {"fov_axis": "s.value"}},
               "p": {"type": "print", "inputs": {"value": "c.camera"}}"#,
            1,
            vec!["'c' (camera)", "fov_axis", "diagonal"],
        ),
        node_case(
            "0/0 in a math node feeding a simulation",
            r#""x": {"type": "value_float", "params": {"value": 0.0}},
               "z": {"type": "math", "params": {"op": "div"}, "inputs": {"a": "x.value", "b": "x.value"}},
               "g": {"type": "mesh_grid"},
               "c": {"type": "mass_spring", "inputs": {"mesh": "g.mesh", "h": "z.value"}},
               "p": {"type": "print", "inputs": {"value": "c.mesh"}}"#,
            1,
            vec!["'c' (mass_spring)", "h"],
        ),
        node_case(
            "Tutte on a closed mesh",
            r#""g": {"type": "mesh_load", "params": {"path": "cube.obj"}},
               "t": {"type": "tutte", "inputs": {"mesh": "g.mesh"}},
               "p": {"type": "print", "inputs": {"value": "t.mesh"}}"#,
            1,
            vec!["'t' (tutte)", "boundary"],
        ),
        node_case(
            "ARAP on a non-manifold mesh",
            r#""g": {"type": "mesh_load", "params": {"path": "fan.obj"}},
               "a": {"type": "arap", "inputs": {"mesh": "g.mesh"}},
               "p": {"type": "print", "inputs": {"value": "a.mesh"}}"#,
            1,
            vec!["'a' (arap)", "manifold"],
        ),
        Case {
            args: args(&["run", "graph.json", "--out", "out", "--frames", "0..3"]),
            ..node_case(
                "semi-implicit cloth that explodes",
                r#""g": {"type": "mesh_grid", "params": {"cells_u": 10, "cells_v": 10}},
                   "c": {"type": "mass_spring", "params": {"integrator": "semi_implicit", "h": 0.5, "fixed": "top_corners"}, "inputs": {"mesh": "g.mesh"}},
                   "p": {"type": "print", "inputs": {"value": "c.mesh"}}"#,
                1,
                vec!["'c' (mass_spring)", "unstable"],
            )
        },
        Case {
            args: args(&["run", "graph.json", "--out", "out", "--max-memory", "1G"]),
            ..node_case(
                "render of 16384 x 16384 over --max-memory 1G",
                r#""g": {"type": "mesh_grid"},
                   "cam": {"type": "camera", "params": {"width": 16384, "height": 16384}},
                   "s": {"type": "scene", "inputs": {"meshes": "g.mesh", "camera": "cam.camera"}},
                   "r": {"type": "render_raster", "inputs": {"scene": "s.scene"}},
                   "p": {"type": "print", "inputs": {"value": "r.color"}}"#,
                1,
                vec!["'r' (render_raster)", "16384x16384", "over the 1 GB limit"],
            )
        },
        Case {
            args: args(&["run", "graph.json", "--out", "out", "--max-memory", "1G"]),
            ..node_case(
                "path tracer of 16384 x 16384 over --max-memory 1G",
                r#""g": {"type": "mesh_grid"},
                   "cam": {"type": "camera", "params": {"width": 16384, "height": 16384}},
                   "s": {"type": "scene", "inputs": {"meshes": "g.mesh", "camera": "cam.camera"}},
                   "r": {"type": "render_path", "inputs": {"scene": "s.scene"}},
                   "p": {"type": "print", "inputs": {"value": "r.color"}}"#,
                1,
                vec!["'r' (render_path)", "over the 1 GB limit"],
            )
        },
    ]
}

/// Plugins that answer badly (the test plugin of tests/data/plugins/misbehave).
fn plugin_cases() -> Vec<Case> {
    let dir = root().join("tests/data/plugins/misbehave");
    let case = |name: &'static str, ty: &str, expect: Vec<&'static str>| Case {
        name,
        reader: "plugin reply",
        files: vec![(
            "graph.json",
            graph(&format!(
                r#""g": {{"type": "mesh_grid"}}, "x": {{"type": "{ty}"{mesh}}},
                   "p": {{"type": "print", "inputs": {{"value": "x.{out}"}}}}"#,
                mesh = if ty == "pl_wrong_shape" || ty == "pl_escape" {
                    r#", "inputs": {"mesh": "g.mesh"}"#
                } else {
                    ""
                },
                out = if ty == "pl_wrong_type" {
                    "count"
                } else if ty == "pl_wrong_shape" || ty == "pl_escape" {
                    "mesh"
                } else {
                    "y"
                }
            )),
        )],
        args: vec![
            "run".into(),
            "graph.json".into(),
            "--out".into(),
            "out".into(),
            "--plugins".into(),
            dir.display().to_string(),
        ],
        exit: 1,
        expect,
    };
    vec![
        case(
            "plugin that raises",
            "pl_crash",
            vec!["'x' (pl_crash)", "ZeroDivisionError"],
        ),
        case(
            "plugin returning a string for an int",
            "pl_wrong_type",
            vec!["'x' (pl_wrong_type)", "count"],
        ),
        case(
            "plugin returning a 1-D array as positions",
            "pl_wrong_shape",
            vec!["'x' (pl_wrong_shape)", "shape"],
        ),
        case(
            "plugin naming a file outside its folder",
            "pl_escape",
            vec!["'x' (pl_escape)", "outside"],
        ),
        case(
            "plugin printing text that is not JSON",
            "pl_bad_json",
            vec!["'x' (pl_bad_json)", "not JSON"],
        ),
        case(
            "plugin speaking another protocol",
            "pl_bad_protocol",
            vec!["'x' (pl_bad_protocol)", "protocol"],
        ),
        case(
            "plugin leaving out an output",
            "pl_missing_output",
            vec!["'x' (pl_missing_output)", "y"],
        ),
    ]
}

/// Plugin manifests (a broken plugin is left out with a warning naming its file, and the
/// graph runs without it) and command lines.
fn cli_cases() -> Vec<Case> {
    let ok_graph = graph(
        r#""m": {"type": "mesh_grid"}, "p": {"type": "print", "inputs": {"value": "m.mesh"}}"#,
    );
    let manifest = |name: &'static str, text: &str, expect: Vec<&'static str>| Case {
        name,
        reader: "plugin manifest",
        files: vec![
            ("plug/cgnodes-plugin.json", text.as_bytes().to_vec()),
            ("graph.json", ok_graph.clone()),
        ],
        args: args(&["run", "graph.json", "--out", "out", "--plugins", "plug"]),
        exit: 0,
        expect,
    };
    let cli = |name: &'static str, a: &[&str], exit: i32, expect: Vec<&'static str>| Case {
        name,
        reader: "command line",
        files: vec![("graph.json", ok_graph.clone())],
        args: args(a),
        exit,
        expect,
    };
    vec![
        manifest(
            "manifest that is not JSON",
            "{ name: plugin",
            vec![
                "warning: plugin not loaded",
                "cgnodes-plugin.json",
                "line 1",
            ],
        ),
        manifest(
            "manifest of another protocol",
            r#"{"name": "p", "version": "1", "protocol": 7, "command": ["true"], "nodes": []}"#,
            vec!["warning: plugin not loaded", "protocol 7"],
        ),
        manifest(
            "manifest shadowing a built-in node",
            r#"{"name": "p", "version": "1", "protocol": 1, "command": ["true"],
                "nodes": [{"type": "mesh_grid", "outputs": [{"name": "y", "type": "float"}]}]}"#,
            vec!["warning", "'mesh_grid' is not added"],
        ),
        manifest(
            "manifest with an unknown socket type",
            r#"{"name": "p", "version": "1", "protocol": 1, "command": ["true"],
                "nodes": [{"type": "p_x", "outputs": [{"name": "y", "type": "quaternion"}]}]}"#,
            vec!["warning: plugin not loaded", "quaternion"],
        ),
        cli(
            "graph file missing",
            &["run", "no_such_graph.json", "--out", "out"],
            3,
            vec!["no_such_graph.json"],
        ),
        cli(
            "graph is a folder",
            &["run", ".", "--out", "out"],
            3,
            vec!["."],
        ),
        cli(
            "frame range reversed",
            &["run", "graph.json", "--out", "out", "--frames", "5..1"],
            2,
            vec!["5..1"],
        ),
        cli(
            "frame range absurd",
            &[
                "run",
                "graph.json",
                "--out",
                "out",
                "--frames",
                "0..99999999999999999999",
            ],
            2,
            vec!["frames"],
        ),
        cli(
            "--set on an unknown node",
            &["run", "graph.json", "--out", "out", "--set", "ghost.x=1"],
            2,
            vec!["ghost"],
        ),
        cli(
            "--set of a bad value",
            &[
                "run",
                "graph.json",
                "--out",
                "out",
                "--set",
                "m.cells_u=many",
            ],
            3,
            vec!["cells_u"],
        ),
        cli(
            "--target unknown",
            &["run", "graph.json", "--out", "out", "--target", "ghost"],
            2,
            vec!["ghost"],
        ),
    ]
}

/// Every case of the corpus.
fn corpus() -> Vec<Case> {
    let mut all = Vec::new();
    all.extend(graph_cases());
    all.extend(f3d_cases());
    all.extend(mesh_cases());
    all.extend(file_cases());
    all.extend(node_cases());
    all.extend(plugin_cases());
    all.extend(cli_cases());
    all
}

/// Support meshes some node cases load.
fn support_files(dir: &Path) {
    let cube = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
                f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
    std::fs::write(dir.join("cube.obj"), cube).unwrap();
    // three triangles sharing one edge: not a manifold
    let fan = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n";
    std::fs::write(dir.join("fan.obj"), fan).unwrap();
}

struct Outcome {
    code: Option<i32>,
    millis: u128,
    text: String,
}

fn run_case(c: &Case, dir: &Path) -> Outcome {
    for (name, bytes) in &c.files {
        let p = dir.join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, bytes).unwrap();
    }
    support_files(dir);
    let t0 = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_cgnodes"))
        .args(&c.args)
        .current_dir(dir)
        .env("CGNODES_PLUGIN_PATH", "")
        .env("RUST_BACKTRACE", "0")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // read both pipes on threads so a chatty case cannot block on a full pipe
    let mut so = child.stdout.take().unwrap();
    let mut se = child.stderr.take().unwrap();
    let ro = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut so, &mut s);
        s
    });
    let re = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut se, &mut s);
        s
    });
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if t0.elapsed() > HANG {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let millis = t0.elapsed().as_millis();
    let text = format!("{}{}", ro.join().unwrap(), re.join().unwrap());
    Outcome {
        code: status.and_then(|s| s.code()),
        millis,
        text,
    }
}

/// Temporary files an interrupted or failed write could leave in `dir`.
fn leftovers(dir: &Path) -> Vec<String> {
    let mut found = Vec::new();
    let Ok(rd) = std::fs::read_dir(dir) else {
        return found;
    };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            found.extend(leftovers(&p));
        } else if p.extension().is_some_and(|x| x == "tmp") {
            found.push(p.display().to_string());
        }
    }
    found
}

#[test]
fn the_bad_input_corpus_gets_clear_errors() {
    let all = corpus();
    assert!(all.len() >= 60, "the corpus has {} cases", all.len());
    let python = Command::new("python3").arg("--version").output().is_ok();
    if !python && ci() {
        panic!("python3 is needed for the plugin cases of the corpus");
    }
    let mut failures = Vec::new();
    let mut report = String::from(
        "# The bad-input corpus: what each case gets\n\n\
         Written by `CGNODES_HOSTILE_REPORT=docs/hostile-corpus.md cargo test --release --test it \
         hostile` (see [reliability.md](reliability.md)); times are wall-clock milliseconds for \
         the whole `cgnodes` process.\n\n\
         | # | reader | case | exit | ms | first error line |\n|---|---|---|---|---|---|\n",
    );
    for (i, c) in all.iter().enumerate() {
        if c.reader == "plugin reply" && !python {
            eprintln!("skipped without python3: {}", c.name);
            continue;
        }
        let dir = tempfile::tempdir().unwrap();
        let o = run_case(c, dir.path());
        let mut bad = Vec::new();
        match o.code {
            None => bad.push(format!("killed after {} ms (hang or signal)", o.millis)),
            Some(101) => bad.push("panicked (exit 101)".to_string()),
            Some(code) if code != c.exit => bad.push(format!("exit {code}, want {}", c.exit)),
            _ => {}
        }
        if o.text.contains("panicked at") {
            bad.push("printed a panic".into());
        }
        for e in &c.expect {
            if !o.text.contains(e) {
                bad.push(format!("no '{e}' in the output"));
            }
        }
        let left = leftovers(dir.path());
        if !left.is_empty() {
            bad.push(format!("left temporary files {left:?}"));
        }
        if !bad.is_empty() {
            failures.push(format!(
                "{} [{}]: {}\n{}",
                c.name,
                c.reader,
                bad.join("; "),
                o.text.trim_end()
            ));
        }
        let first = o
            .text
            .lines()
            .find(|l| l.starts_with("error") || l.starts_with("warning") || l.contains("error:"))
            .or_else(|| o.text.lines().next())
            .unwrap_or("")
            // The case's temporary folder differs each run: written as `<case>`.
            .replace(&dir.path().display().to_string(), "<case>")
            .replace('|', "\\|");
        let first: String = first.chars().take(160).collect();
        let code = o.code.map_or("killed".into(), |c| c.to_string());
        let _ = writeln!(
            report,
            "| {} | {} | {} | {} | {} | `{}` |",
            i + 1,
            c.reader,
            c.name,
            code,
            o.millis,
            first
        );
    }
    if let Some(p) = std::env::var_os("CGNODES_HOSTILE_REPORT") {
        std::fs::write(p, &report).unwrap();
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n\n{}",
        failures.len(),
        all.len(),
        failures.join("\n\n")
    );
}

/// Whether this is a CI run (`CI=1`), where missing tools fail instead of skipping.
fn ci() -> bool {
    std::env::var_os("CI").is_some()
}

/// Every crashing input the fuzz targets found (tests/data/fuzz/<target>/), replayed through
/// the same entry points (`cgnodes::fuzz`) on the stable toolchain: none may panic.
#[test]
fn fuzz_crashes_stay_fixed() {
    let dir = root().join("tests/data/fuzz");
    let scratch = tempfile::tempdir().unwrap();
    let mut n = 0;
    for t in std::fs::read_dir(&dir).unwrap() {
        let t = t.unwrap().path();
        if !t.is_dir() {
            continue;
        }
        let target = t.file_name().unwrap().to_str().unwrap().to_string();
        for f in std::fs::read_dir(&t).unwrap() {
            let f = f.unwrap().path();
            let data = std::fs::read(&f).unwrap();
            assert!(
                cgnodes::fuzz::run(&target, &data, scratch.path()),
                "{}: no fuzz target '{target}'",
                f.display()
            );
            n += 1;
        }
    }
    assert!(
        n >= 4,
        "only {n} fuzz regressions found in {}",
        dir.display()
    );
}
