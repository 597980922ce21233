//! The graph format's JSON Schema with every node type of a registry spelt out, so that an
//! editor completes node types, parameter names and choices, and flags a misspelt parameter
//! or an out-of-range value before anything runs (`cgnodes schema`, `docs/graph.schema.json`).
//!
//! Each node type becomes a `oneOf` branch of `$defs/NodeSpec`: its `type` as a constant, its
//! `params` as the input sockets that take literals (typed as `Value::from_json` parses them,
//! with the declaration's range, choices, default and doc), its `inputs` as the input socket
//! names; both refuse other keys, as validation does.

use cgnodes_api::node::{NodeDecl, SocketDecl};
use cgnodes_api::registry::Registry;
use cgnodes_api::types::SocketType;
use serde_json::{json, Map, Value};

/// The literal a socket of type `ty` accepts in `params`, or `None` if it only takes links.
pub fn literal_schema(ty: &SocketType) -> Option<Value> {
    use SocketType as T;
    let vector = |n: usize| {
        json!({"anyOf": [
            {"type": "number"},
            {"type": "array", "items": {"type": "number"}, "minItems": n, "maxItems": n}
        ]})
    };
    Some(match ty {
        T::Bool => json!({"type": "boolean"}),
        T::Int => json!({"type": "integer"}),
        T::Float => json!({"type": "number"}),
        T::String => json!({"type": "string"}),
        T::Vec2 => vector(2),
        T::Vec3 | T::Color => vector(3),
        T::List(inner) => {
            let item = literal_schema(inner)?;
            json!({"anyOf": [{"type": "array", "items": item.clone()}, item]})
        }
        T::Any => json!({"type": ["boolean", "number", "string"]}),
        _ => return None,
    })
}

/// The schema of one parameter: its literal form plus range, choices, default and doc.
fn param_schema(s: &SocketDecl) -> Option<Value> {
    let mut v = literal_schema(&s.ty)?;
    let o = v.as_object_mut()?;
    if let Some(lo) = s.min {
        o.insert("minimum".into(), json!(lo));
    }
    if let Some(hi) = s.max {
        o.insert("maximum".into(), json!(hi));
    }
    if let Some(c) = &s.choices {
        o.insert("enum".into(), json!(c));
    }
    if let Some(d) = &s.default {
        o.insert("default".into(), d.clone());
    }
    let doc = format!("{} ({})", s.doc, s.ty);
    o.insert("description".into(), json!(doc.trim_start()));
    Some(v)
}

/// The `oneOf` branch of one node type.
pub fn node_schema(d: &NodeDecl) -> Value {
    let mut params = Map::new();
    let mut inputs = Map::new();
    for s in &d.inputs {
        if let Some(p) = param_schema(s) {
            params.insert(s.name.clone(), p);
        }
        let doc = format!("{} ({}); a link \"<node id>.<output socket>\"", s.doc, s.ty);
        inputs.insert(
            s.name.clone(),
            json!({"$ref": "#/$defs/LinkSpec", "description": doc.trim_start()}),
        );
    }
    json!({
        "type": "object",
        "description": d.doc,
        "properties": {
            "type": {"const": d.type_name},
            "params": {"type": "object", "properties": params, "additionalProperties": false},
            "inputs": {"type": "object", "properties": inputs, "additionalProperties": false},
            "meta": {"description": "Free-form data (editor position); ignored by the runtime."}
        },
        "required": ["type"],
        "additionalProperties": false
    })
}

/// The graph format's schema (`format::schema`) with `NodeSpec` typed by `registry`.
pub fn typed_schema(registry: &Registry) -> Value {
    let mut s = super::format::schema();
    let mut defs = s
        .get("$defs")
        .and_then(Value::as_object)
        .cloned()
        .unwrap_or_default();
    let mut branches = Vec::new();
    for d in registry.iter() {
        let key = format!("node:{}", d.type_name);
        branches.push(json!({"$ref": format!("#/$defs/{key}")}));
        defs.insert(key, node_schema(d));
    }
    let names: Vec<&str> = registry.iter().map(|d| d.type_name.as_str()).collect();
    defs.insert(
        "NodeSpec".into(),
        json!({
            "description": "One node of a graph: its type, literal parameters and links.",
            "type": "object",
            "properties": {"type": {"description": "Node type, as `cgnodes nodes` lists them.", "enum": names}},
            "required": ["type"],
            "oneOf": branches
        }),
    );
    if let Some(o) = s.as_object_mut() {
        o.insert("$defs".into(), Value::Object(defs));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sockets_become_typed_parameters() {
        let reg = crate::test_registry();
        let s = typed_schema(&reg);
        let defs = &s["$defs"];
        // every node type has a branch, and the type enum lists them all
        assert_eq!(
            defs["NodeSpec"]["oneOf"].as_array().map(Vec::len),
            Some(reg.len())
        );
        let arap = &defs["node:arap"]["properties"];
        assert_eq!(arap["type"]["const"], "arap");
        // a mesh input takes only links; a number has its range
        assert!(arap["params"]["properties"].get("mesh").is_none());
        assert!(arap["inputs"]["properties"].get("mesh").is_some());
        // ranges and choices carried over (mesh_grid has both)
        let grid = &defs["node:mesh_grid"]["properties"]["params"]["properties"];
        let decl = reg.get("mesh_grid").unwrap();
        for sock in &decl.inputs {
            let p = &grid[&sock.name];
            if let Some(lo) = sock.min {
                assert_eq!(p["minimum"].as_f64(), Some(lo), "{}", sock.name);
            }
            if let Some(c) = &sock.choices {
                assert_eq!(p["enum"], json!(c), "{}", sock.name);
            }
        }
        assert!(decl.inputs.iter().any(|s| s.min.is_some()));
        assert!(decl.inputs.iter().any(|s| s.choices.is_some()));
    }

    #[test]
    fn literal_forms_follow_the_parser() {
        use SocketType as T;
        assert_eq!(literal_schema(&T::Int), Some(json!({"type": "integer"})));
        assert!(literal_schema(&T::Mesh).is_none());
        assert!(literal_schema(&T::List(Box::new(T::Image))).is_none());
        let v3 = literal_schema(&T::Vec3).unwrap();
        assert_eq!(v3["anyOf"][1]["minItems"], 3);
    }
}
