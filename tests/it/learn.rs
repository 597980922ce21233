//! Issue 26, networks through the runtime: the insect data trained and evaluated as the
//! course asks, a model saved and loaded back with the same predictions, and bad input
//! (a label column that is not integer, test classes unseen in training) refused with the
//! socket named. The gradient check, the separable toy set and seed reproducibility are the
//! unit tests of `nodes/learn/mlp.rs`.

use crate::common::{asset, run_graph};
use cgnodes::exec::NodeStatus;
use cgnodes::nodes::builtin_registry;

fn run(dir: &std::path::Path, nodes: &str) -> cgnodes::exec::RunReport {
    let text = format!(r#"{{"format":"cgnodes-graph","version":1,"nodes":{nodes}}}"#);
    run_graph(&text, &builtin_registry(), dir, &dir.join("out"), 1, 0..=0).remove(0)
}

#[test]
fn insects_train_save_load_and_predict_the_same() {
    let dir = tempfile::tempdir().unwrap();
    let tr = asset("assets/insects/insects-training.txt");
    let te = asset("assets/insects/insects-testing.txt");
    let nodes = format!(
        r#"{{"train":{{"type":"table_load","params":{{"path":"{}"}}}},
        "test":{{"type":"table_load","params":{{"path":"{}"}}}},
        "mlp":{{"type":"classifier_train","params":{{"hidden":[16,16],"activation":"relu","learning_rate":0.01,"epochs":30,"seed":3}},
                "inputs":{{"train":"train.table","test":"test.table"}}}},
        "save":{{"type":"model_save","params":{{"path":"m.json"}},"inputs":{{"model":"mlp.model"}}}},
        "p":{{"type":"classifier_predict","inputs":{{"model":"mlp.model","data":"test.table"}}}},
        "w":{{"type":"table_write","params":{{"path":"p.csv"}},"inputs":{{"value":"p.labels"}}}},
        "wt":{{"type":"table_write","params":{{"path":"acc.csv"}},"inputs":{{"value":"p.table"}}}},
        "wl":{{"type":"table_write","params":{{"path":"log.csv"}},"inputs":{{"value":"mlp.log"}}}}}}"#,
        tr.display(),
        te.display()
    );
    let rep = run(dir.path(), &nodes);
    assert!(rep.errors().is_empty(), "{:?}", rep.errors());
    let acc = std::fs::read_to_string(dir.path().join("out/acc.csv")).unwrap();
    let a: f64 = acc
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .nth(2)
        .unwrap()
        .parse()
        .unwrap();
    assert!(a > 0.9, "test accuracy {a}");
    // The log's loss decreases over the epochs.
    let log = std::fs::read_to_string(dir.path().join("out/log.csv")).unwrap();
    let loss: Vec<f64> = log
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
        .collect();
    assert_eq!(loss.len(), 30);
    assert!(loss[29] < 0.5 * loss[0], "{loss:?}");
    // model_load gives back a model that predicts the same labels.
    let saved = std::fs::read_to_string(dir.path().join("out/p.csv")).unwrap();
    let nodes = format!(
        r#"{{"test":{{"type":"table_load","params":{{"path":"{}"}}}},
        "load":{{"type":"model_load","params":{{"path":"out/m.json"}}}},
        "p":{{"type":"classifier_predict","inputs":{{"model":"load.model","data":"test.table"}}}},
        "w":{{"type":"table_write","params":{{"path":"q.csv"}},"inputs":{{"value":"p.labels"}}}}}}"#,
        te.display()
    );
    let rep = run(dir.path(), &nodes);
    assert!(rep.errors().is_empty(), "{:?}", rep.errors());
    assert_eq!(
        std::fs::read_to_string(dir.path().join("out/q.csv")).unwrap(),
        saved
    );
}

#[test]
fn bad_labels_are_refused_naming_the_socket() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("frac.txt"), "0 0 0\n1 1 0.5\n2 2 1\n").unwrap();
    std::fs::write(dir.path().join("tr.txt"), "0 0 0\n1 1 1\n2 2 1\n").unwrap();
    std::fs::write(dir.path().join("te.txt"), "0 0 0\n1 1 2\n").unwrap();
    let rep = run(
        dir.path(),
        r#"{"frac":{"type":"table_load","params":{"path":"frac.txt"}},
        "tr":{"type":"table_load","params":{"path":"tr.txt"}},
        "te":{"type":"table_load","params":{"path":"te.txt"}},
        "a":{"type":"classifier_train","params":{"epochs":2},"inputs":{"train":"frac.table"}},
        "b":{"type":"classifier_train","params":{"epochs":2},"inputs":{"train":"tr.table","test":"te.table"}},
        "c":{"type":"classifier_train","params":{"epochs":2,"label_column":"c7"},"inputs":{"train":"tr.table"}},
        "pa":{"type":"print","inputs":{"value":"a.log"}},
        "pb":{"type":"print","inputs":{"value":"b.log"}},
        "pc":{"type":"print","inputs":{"value":"c.log"}}}"#,
    );
    let fail = |id: &str| match &rep.node(id).unwrap().status {
        NodeStatus::Failed(e) => e.clone(),
        other => panic!("{id}: {other:?}"),
    };
    let e = fail("a");
    assert_eq!(e.socket.as_deref(), Some("label_column"));
    assert!(e.message.contains("0.5 is not an integer"), "{}", e.message);
    let e = fail("b");
    assert_eq!(e.socket.as_deref(), Some("test"));
    assert!(
        e.message
            .contains("label 2 is not among the training classes"),
        "{}",
        e.message
    );
    assert_eq!(fail("c").socket.as_deref(), Some("label_column"));
}
