//! Validation of the part of a graph that a run needs: a node that no requested output
//! needs does not run, so a problem in it (a missing file, an unknown type, a bad literal)
//! is a warning for that run, not a reason to refuse the graph (issue 23).

use super::{validate_with, GraphError, ValidGraph};
use crate::graph::format::{split_link, Graph};
use cgnodes_api::registry::Registry;
use std::collections::BTreeSet;
use std::path::PathBuf;

/// Validates what `targets` (or, when `None`, the graph's `outputs`, else every sink) need.
/// A graph that validates whole comes back with no warnings. Otherwise, when the errors all
/// lie in nodes the run does not need, the graph comes back reduced to the needed nodes,
/// with the errors of the rest as warnings; when the needed part has errors, those are the
/// `Err`. When which nodes are needed cannot be told (an unknown node type and no
/// `outputs`, or `outputs` naming a missing node), every error stays an error.
pub fn validate_needed(
    graph: &Graph,
    registry: &Registry,
    asset_dirs: &[PathBuf],
    targets: Option<&[String]>,
) -> Result<(ValidGraph, Vec<GraphError>), Vec<GraphError>> {
    let all = match validate_with(graph, registry, asset_dirs) {
        Ok(v) => return Ok((v, Vec::new())),
        Err(e) => e,
    };
    let Some(roots) = roots(graph, registry, targets) else {
        return Err(all);
    };
    let keep = needed(graph, &roots);
    if keep.len() == graph.spec.nodes.len() {
        return Err(all);
    }
    let mut part = graph.clone();
    part.spec.nodes.retain(|id, _| keep.contains(id));
    part.spec.outputs = Some(roots);
    let valid = validate_with(&part, registry, asset_dirs)?;
    Ok((valid, all))
}

/// The ids a run asks for, or `None` when they cannot be told.
fn roots(graph: &Graph, registry: &Registry, targets: Option<&[String]>) -> Option<Vec<String>> {
    let spec = &graph.spec;
    let ids: Vec<String> = match (targets, &spec.outputs) {
        (Some(t), _) => t.to_vec(),
        (None, Some(outs)) => {
            if outs.iter().any(|o| !spec.nodes.contains_key(o)) {
                return None;
            }
            outs.clone()
        }
        (None, None) => {
            let mut sinks = Vec::new();
            for (id, n) in &spec.nodes {
                match registry.get(&n.node_type) {
                    Some(d) if d.sink => sinks.push(id.clone()),
                    Some(_) => {}
                    None => return None,
                }
            }
            sinks
        }
    };
    // A --target that is no node is the caller's error to report; it needs nothing here.
    Some(
        ids.into_iter()
            .filter(|id| spec.nodes.contains_key(id))
            .collect(),
    )
}

/// The roots and every node upstream of them, following the links as written.
fn needed(graph: &Graph, roots: &[String]) -> BTreeSet<String> {
    let mut keep = BTreeSet::new();
    let mut stack: Vec<&str> = roots.iter().map(String::as_str).collect();
    while let Some(id) = stack.pop() {
        let Some(n) = graph.spec.nodes.get(id) else {
            continue;
        };
        if !keep.insert(id.to_string()) {
            continue;
        }
        for l in n.inputs.values() {
            for link in l.links() {
                if let Some((from, _)) = split_link(link) {
                    stack.push(from);
                }
            }
        }
    }
    keep
}

#[cfg(test)]
mod tests {
    use super::*;

    fn graph(text: &str) -> Graph {
        let dir = std::env::temp_dir();
        crate::graph::parse(text, &dir.join("g.json"), &dir).unwrap()
    }

    const TEXT: &str = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
        "x": {"type": "value_float", "params": {"value": 2}},
        "w": {"type": "print", "inputs": {"value": "x.value"}},
        "m": {"type": "mesh_load", "params": {"path": "no/such/file.obj"}},
        "bad": {"type": "no_such_type"},
        "s": {"type": "mesh_save", "inputs": {"mesh": "m.mesh"}, "params": {"path": "o.obj"}}
    }}"#;

    #[test]
    fn problems_outside_the_targets_are_warnings() {
        let reg = crate::test_registry();
        let g = graph(TEXT);
        let t = ["w".to_string()];
        let (v, warnings) = validate_needed(&g, &reg, &[], Some(&t)).unwrap();
        let ids: Vec<&str> = v.nodes.iter().map(|n| n.id.as_str()).collect();
        assert_eq!(ids, ["x", "w"]);
        let nodes: BTreeSet<_> = warnings.iter().filter_map(|w| w.node()).collect();
        assert_eq!(nodes, BTreeSet::from(["bad", "m"]));
    }

    #[test]
    fn problems_in_the_needed_part_stay_errors() {
        let reg = crate::test_registry();
        let g = graph(TEXT);
        let t = ["s".to_string()];
        let errs = validate_needed(&g, &reg, &[], Some(&t)).unwrap_err();
        assert_eq!(errs.len(), 1, "{errs:?}");
        assert!(matches!(&errs[0], GraphError::MissingFile { node, .. } if node == "m"));
        // Without targets or outputs an unknown type could be a sink: nothing is dropped.
        let errs = validate_needed(&g, &reg, &[], None).unwrap_err();
        assert_eq!(errs.len(), 2, "{errs:?}");
    }
}
