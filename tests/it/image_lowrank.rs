//! `seam_carve`, `image_svd` and `rpca` through the node interface: tables, warnings (rank
//! clamped, RPCA not converged), the CSV matrix input, and errors naming their socket.

use crate::common::{run_node, NodeOutputs};
use cgnodes::node::FileEnv;
use cgnodes::types::{Image, Table, Value};
use std::collections::BTreeMap;

/// Runs node `name` outside a graph: its outputs and log lines, or the error text.
fn run(name: &str, inputs: Vec<(&str, Value)>) -> Result<NodeOutputs, String> {
    run_node(name, inputs, &FileEnv::default())
}

fn table(out: &BTreeMap<String, Value>, socket: &str) -> Table {
    match &out[socket] {
        Value::Table(t) => (**t).clone(),
        v => panic!("table expected, got {v:?}"),
    }
}

fn image(out: &BTreeMap<String, Value>, socket: &str) -> Image {
    match &out[socket] {
        Value::Image(i) => (**i).clone(),
        v => panic!("image expected, got {v:?}"),
    }
}

fn picture(w: u32, h: u32) -> Image {
    let mut img = Image::new(w, h, [0.0, 0.0, 0.0, 1.0]);
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x as f32 / w as f32, y as f32 / h as f32);
            img.set(x, y, [fx, (fx * 9.0 + fy * 4.0).sin().abs(), fy * fy, 1.0]);
        }
    }
    img
}

#[test]
fn image_svd_clamps_the_rank_with_a_warning() {
    let img = picture(12, 9);
    let ins = vec![
        ("image", Value::from(img.clone())),
        ("rank", Value::Int(40)),
    ];
    let (out, logs) = run("image_svd", ins).unwrap();
    assert!(
        logs.iter()
            .any(|l| l.contains("warning") && l.contains("clamped to 9")),
        "{logs:?}"
    );
    let t = table(&out, "table");
    assert_eq!(t.column("rank").unwrap(), &[9.0, 9.0, 9.0]);
    // full rank: the picture back (f32 storage)
    let back = image(&out, "image");
    let worst = back
        .pixels
        .iter()
        .zip(&img.pixels)
        .flat_map(|(a, b)| (0..4).map(move |c| (a[c] - b[c]).abs()));
    assert!(worst.fold(0.0f32, f32::max) < 1e-5);
    assert_eq!(table(&out, "singular_values").column("g").unwrap().len(), 9);
    let e = run(
        "image_svd",
        vec![("image", Value::from(Image::new(0, 3, [0.0; 4])))],
    )
    .unwrap_err();
    assert!(e.contains("socket 'image'"), "{e}");
}

#[test]
fn rpca_reads_a_csv_matrix_and_reports_errors_on_it() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        Value::from(&*p.to_string_lossy())
    };
    // rank 1 plus one outlier
    let mut text = String::new();
    for i in 0..12 {
        let row: Vec<String> = (0..10)
            .map(|j| {
                let v = (i as f64 + 1.0) * (j as f64 + 1.0) / 10.0
                    + if (i, j) == (4, 6) { 30.0 } else { 0.0 };
                format!("{v}")
            })
            .collect();
        text.push_str(&row.join(","));
        text.push('\n');
    }
    let ins = vec![
        ("matrix", write("m.csv", &text)),
        ("tolerance", Value::Float(1e-9)),
    ];
    let (out, logs) = run("rpca", ins).unwrap();
    assert!(logs.is_empty(), "{logs:?}");
    let s = table(&out, "sparse_matrix");
    assert_eq!(s.columns.len(), 10);
    assert!((s.column("c7").unwrap()[4] - 30.0).abs() < 1e-3);
    let log = table(&out, "log");
    assert_eq!(*log.column("rank").unwrap().last().unwrap(), 1.0);
    assert_eq!(
        (
            image(&out, "low_rank").width,
            image(&out, "low_rank").height
        ),
        (10, 12)
    );
    // not converged: a warning with the residuals
    let ins = vec![
        ("matrix", write("m2.csv", &text)),
        ("max_iterations", Value::Int(2)),
    ];
    let (_, logs) = run("rpca", ins).unwrap();
    assert!(
        logs.iter()
            .any(|l| l.contains("did not converge in 2 iterations")),
        "{logs:?}"
    );
    // bad matrices
    for (bad, what) in [
        ("1,2,3\n4,5\n", "row 2 has 2 numbers"),
        ("1,2\nnan,4\n", "not finite"),
    ] {
        let e = run("rpca", vec![("matrix", write("bad.csv", bad))]).unwrap_err();
        assert!(e.contains("socket 'matrix'") && e.contains(what), "{e}");
    }
    let e = run("rpca", vec![]).unwrap_err();
    assert!(e.contains("socket 'image'"), "{e}");
}

#[test]
fn seam_carve_table_and_errors() {
    let img = picture(20, 12);
    let ins = vec![
        ("image", Value::from(img.clone())),
        ("width", Value::Int(15)),
        ("height", Value::Int(14)),
    ];
    let (out, _) = run("seam_carve", ins).unwrap();
    let t = table(&out, "table");
    assert_eq!(t.column("seams_removed").unwrap(), &[5.0]);
    assert_eq!(t.column("seams_inserted").unwrap(), &[2.0]);
    let r = image(&out, "image");
    assert_eq!((r.width, r.height), (15, 14));
    let seams = image(&out, "seams");
    assert_eq!((seams.width, seams.height), (20, 12));
    let e = run(
        "seam_carve",
        vec![
            ("image", Value::from(img.clone())),
            ("height", Value::Int(5)),
        ],
    )
    .unwrap_err();
    assert!(e.contains("socket 'width'"), "{e}");
    let ins = vec![
        ("image", Value::from(img)),
        ("width", Value::Int(10)),
        ("height", Value::Int(12)),
        ("protect", Value::from(Image::new(20, 11, [1.0; 4]))),
    ];
    let e = run("seam_carve", ins).unwrap_err();
    assert!(e.contains("socket 'protect'") && e.contains("20x11"), "{e}");
}
