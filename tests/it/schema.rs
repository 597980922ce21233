//! The typed JSON Schema (`cgnodes schema`) checked by an independent validator, Python's
//! `jsonschema` (installed by `.ci/run`): every example graph passes, and a misspelt
//! parameter, an out-of-range value, a wrong choice, a wrong literal type and an unknown node
//! type are each refused.

use crate::common::{root, skip_or_fail};
use std::process::Command;

const CHECK: &str = r#"
import json, sys, glob
from jsonschema import Draft202012Validator
schema = json.load(open(sys.argv[1]))
Draft202012Validator.check_schema(schema)
v = Draft202012Validator(schema)
out = {"graphs": {}, "cases": {}}
for path in sorted(glob.glob(sys.argv[2] + "/*.json")):
    g = json.load(open(path))
    if g.get("format") == "cgnodes-graph":
        out["graphs"][path] = [e.message[:200] for e in v.iter_errors(g)]
for name, g in json.load(open(sys.argv[3])).items():
    out["cases"][name] = v.is_valid(g)
print(json.dumps(out))
"#;

fn graph(node: serde_json::Value) -> serde_json::Value {
    serde_json::json!({"format": "cgnodes-graph", "version": 1, "nodes": {"a": node}})
}

#[test]
fn an_independent_validator_accepts_the_examples_and_refuses_mistakes() {
    if Command::new("python3")
        .args(["-c", "import jsonschema"])
        .output()
        .map(|o| !o.status.success())
        .unwrap_or(true)
    {
        return skip_or_fail(
            "typed schema",
            "python3 with jsonschema is missing (pip install jsonschema)",
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let schema = cgnodes::graph::typed_schema(&cgnodes::nodes::builtin_registry());
    let schema_path = dir.path().join("schema.json");
    std::fs::write(&schema_path, schema.to_string()).unwrap();
    use serde_json::json;
    let cases = json!({
        "valid": graph(json!({"type": "mesh_grid",
            "params": {"cells_u": 4, "cells_v": 5, "plane": "xz", "size": [1, 2], "center": 0.5}})),
        "misspelt": graph(json!({"type": "mesh_grid", "params": {"cellz_u": 4}})),
        "out_of_range": graph(json!({"type": "mesh_grid", "params": {"cells_u": 0}})),
        "bad_choice": graph(json!({"type": "mesh_grid", "params": {"plane": "xw"}})),
        "wrong_type": graph(json!({"type": "mesh_grid", "params": {"cells_u": "four"}})),
        "unknown_type": graph(json!({"type": "mesh_gird"})),
        "unknown_input": graph(json!({"type": "arap", "inputs": {"meshh": "x.mesh"}})),
        "mesh_as_literal": graph(json!({"type": "arap", "params": {"mesh": "bunny.obj"}})),
    });
    let cases_path = dir.path().join("cases.json");
    std::fs::write(&cases_path, cases.to_string()).unwrap();
    let o = Command::new("python3")
        .args(["-c", CHECK])
        .arg(&schema_path)
        .arg(root().join("graphs"))
        .arg(&cases_path)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let graphs = r["graphs"].as_object().unwrap();
    assert!(graphs.len() >= 20, "{} example graphs", graphs.len());
    for (path, errors) in graphs {
        assert_eq!(errors, &json!([]), "{path} does not match the schema");
    }
    let c = &r["cases"];
    assert_eq!(c["valid"], true);
    for bad in [
        "misspelt",
        "out_of_range",
        "bad_choice",
        "wrong_type",
        "unknown_type",
        "unknown_input",
        "mesh_as_literal",
    ] {
        assert_eq!(c[bad], false, "{bad} was accepted");
    }
}
