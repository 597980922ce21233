//! Issue 26, curves and fitting through the runtime: points read from the shipped file, a
//! curve written as CSV columns x, y, a plot written, and bad input refused with the socket
//! named. The algorithms' own checks (interpolation to 1e-10, natural ends, hand-computed
//! parameterizations, exact polynomial fits) are the unit tests of `nodes/curve/`.

use crate::common::{asset, run_graph};
use cgnodes::exec::NodeStatus;
use cgnodes::node::NodeError;
use cgnodes::nodes::builtin_registry;

/// Runs `nodes` (the JSON of a graph's node map) in a fresh folder; returns the report and the
/// output folder.
fn run(nodes: &str) -> (cgnodes::exec::RunReport, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let text = format!(r#"{{"format":"cgnodes-graph","version":1,"nodes":{nodes}}}"#);
    let out = dir.path().join("out");
    let mut reps = run_graph(&text, &builtin_registry(), dir.path(), &out, 1, 0..=0);
    (reps.remove(0), dir)
}

fn failure(rep: &cgnodes::exec::RunReport, id: &str) -> NodeError {
    match &rep.node(id).unwrap().status {
        NodeStatus::Failed(e) => e.clone(),
        other => panic!("{id}: {other:?}"),
    }
}

#[test]
fn a_spline_through_the_shipped_points_is_written_as_x_y_columns() {
    let file = asset("assets/curves/points12.txt");
    let nodes = format!(
        r#"{{"load":{{"type":"points_load","params":{{"path":"{}"}}}},
        "c":{{"type":"curve_interpolate","params":{{"method":"cubic_spline","end":"natural","samples":50}},
              "inputs":{{"points":"load.points"}}}},
        "w":{{"type":"table_write","params":{{"path":"c.csv"}},"inputs":{{"value":"c.curve"}}}},
        "p":{{"type":"plot","params":{{"path":"c.svg","label_1":"spline","label_2":"points",
              "style_2":"markers","axes":"equal"}},
              "inputs":{{"series_1":"c.curve","series_2":"load.points"}}}}}}"#,
        file.display()
    );
    let (rep, dir) = run(&nodes);
    assert!(rep.errors().is_empty(), "{:?}", rep.errors());
    let text = std::fs::read_to_string(dir.path().join("out/c.csv")).unwrap();
    let rows: Vec<&str> = text.lines().collect();
    assert_eq!(rows[0], "x,y");
    assert_eq!(rows.len(), 51);
    // The first and last samples are at t_0 and t_{n-1}: the file's first and last points.
    assert_eq!(rows[1], "0,0");
    assert_eq!(rows[50], "13,0");
    let svg = std::fs::read_to_string(dir.path().join("out/c.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("spline"));
}

#[test]
fn bad_input_is_refused_naming_the_socket() {
    let (rep, dir) = run(
        r#"{"rep":{"type":"curve_parameterize","params":{"points":[[0,0],[1,1],[1,1],[2,0]]}},
        "one":{"type":"curve_interpolate","params":{"points":[[0,0]]}},
        "few":{"type":"data_fit","params":{"points":[[0,0],[1,1],[2,4]],"model":"polynomial","degree":3}},
        "t":{"type":"curve_interpolate","params":{"points":[[0,0],[1,1],[2,0]],"t":[0,0.5,0.5]}},
        "w1":{"type":"print","inputs":{"value":"rep.t"}},
        "w2":{"type":"print","inputs":{"value":"one.curve"}},
        "w3":{"type":"print","inputs":{"value":"few.coefficients"}},
        "w4":{"type":"print","inputs":{"value":"t.curve"}}}"#,
    );
    let _ = dir;
    let e = failure(&rep, "rep");
    assert_eq!(e.socket.as_deref(), Some("points"));
    assert!(e.message.contains("points 1 and 2"), "{}", e.message);
    assert_eq!(failure(&rep, "one").socket.as_deref(), Some("points"));
    let e = failure(&rep, "few");
    assert_eq!(e.socket.as_deref(), Some("degree"));
    assert!(e.message.contains("at least 4 distinct x"), "{}", e.message);
    let e = failure(&rep, "t");
    assert_eq!(e.socket.as_deref(), Some("t"));
}

#[test]
fn file_content_errors_name_row_and_socket() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bad.txt"), "1 2\n3 nan\n").unwrap();
    std::fs::write(dir.path().join("labels.txt"), "1 2 0\n3 4 1.5\n").unwrap();
    let text = r#"{"format":"cgnodes-graph","version":1,"nodes":{
        "nan":{"type":"table_load","params":{"path":"bad.txt"}},
        "lab":{"type":"points_load","params":{"path":"labels.txt"}},
        "w5":{"type":"print","inputs":{"value":"nan.table"}},
        "w6":{"type":"print","inputs":{"value":"lab.labels"}}}}"#;
    let out = dir.path().join("out");
    let rep = run_graph(text, &builtin_registry(), dir.path(), &out, 1, 0..=0).remove(0);
    let e = failure(&rep, "nan");
    assert_eq!(e.socket.as_deref(), Some("path"));
    assert!(
        e.message.contains("row 2, column 1: 'nan'"),
        "{}",
        e.message
    );
    let e = failure(&rep, "lab");
    assert_eq!(e.socket.as_deref(), Some("label_column"));
    assert!(
        e.message.contains("label 1.5 is not an integer"),
        "{}",
        e.message
    );
}
