//! Issue 58: a node's socket declaration is the one place its defaults and ranges live. Every
//! declared default lies in its own range and choices, and every built-in node that can be
//! fed runs from its declaration alone: no parameter given, only the required inputs that have
//! no default linked to a small upstream node. A node that refused one of its own defaults
//! (a default repeated, and drifted, in the node's code) fails this test, naming the socket.

use crate::common::{run_graph, stand_in, stand_in_nodes};
use cgnodes::exec::NodeStatus;
use cgnodes::node::{ErrorKind, FileRole};
use std::collections::BTreeMap;

/// Each default parses as its socket's type and passes the check the runtime applies to a
/// literal (range and choices).
#[test]
fn every_declared_default_is_in_its_own_range_and_choices() {
    let registry = cgnodes::nodes::builtin_registry();
    let mut checked = 0;
    for decl in registry.iter() {
        for s in decl.inputs.iter().filter(|s| s.default.is_some()) {
            let v = s.default_value().unwrap_or_else(|| {
                panic!(
                    "{}.{}: default {:?} is not a {:?}",
                    decl.type_name, s.name, s.default, s.ty
                )
            });
            if let Err(e) = s.check_literal(&v) {
                panic!("{}.{}: default refused: {e}", decl.type_name, s.name);
            }
            checked += 1;
        }
    }
    assert!(checked > 300, "only {checked} defaults declared");
}

/// Every node that can be fed runs for frame 0 with its declared defaults. A failure is
/// allowed only where it comes from what the test links in (a stand-in mesh, table or image
/// the node cannot use) or from a file socket whose default names no file here; a node
/// refusing a socket the graph left at its default is a drift between declaration and code.
#[test]
fn every_node_runs_on_its_declared_defaults() {
    let registry = cgnodes::nodes::builtin_registry();
    let mut nodes = stand_in_nodes();
    // Node id -> (type, the sockets the test linked).
    let mut tested: BTreeMap<String, (String, Vec<String>)> = BTreeMap::new();
    let mut skipped = Vec::new();
    for decl in registry.iter() {
        let mut inputs = serde_json::Map::new();
        let mut linked = Vec::new();
        let mut feedable = true;
        for s in &decl.inputs {
            if s.optional || s.default.is_some() {
                continue;
            }
            match stand_in(&s.ty) {
                Some(p) => {
                    inputs.insert(s.name.clone(), p.into());
                    linked.push(s.name.clone());
                }
                None => feedable = false,
            }
        }
        if !feedable {
            skipped.push(decl.type_name.clone());
            continue;
        }
        let id = format!("t_{}", decl.type_name);
        nodes[&id] = serde_json::json!({"type": decl.type_name, "inputs": inputs});
        tested.insert(id, (decl.type_name.clone(), linked));
    }
    assert!(
        tested.len() * 5 >= registry.len() * 4,
        "{} of {} node types fed; skipped {skipped:?}",
        tested.len(),
        registry.len()
    );
    let outputs: Vec<&String> = tested.keys().collect();
    let text = serde_json::json!({"format": "cgnodes-graph", "version": 1,
        "nodes": nodes, "outputs": outputs})
    .to_string();
    let dir = tempfile::tempdir().unwrap();
    let rep = run_graph(
        &text,
        &registry,
        dir.path(),
        &dir.path().join("out"),
        2,
        0..=0,
    )
    .remove(0);
    // Defaults that stand for "the input decides": the node's target width is the image's
    // own unless a remove mask is given (seam_carve refuses a no-op), and set_vert_color's
    // attribute is named by the mesh a user links, which the stand-in grid does not carry.
    let input_decides = ["seam_carve.width", "set_vert_color.attribute"];
    let mut ran = 0;
    let mut drifted = Vec::new();
    for (id, (ty, linked)) in &tested {
        let decl = registry.get(ty).unwrap();
        match &rep.node(id).unwrap().status {
            NodeStatus::Ran | NodeStatus::Cached => ran += 1,
            NodeStatus::Failed(e) => {
                let Some(socket) = e.socket.as_deref() else {
                    continue;
                };
                // Only a socket left at its declared default can drift; a file socket's
                // default names no file here, and an optional socket left empty is the
                // node asking for one of its alternatives.
                let defaulted = decl
                    .inputs
                    .iter()
                    .any(|s| s.name == socket && s.default.is_some() && s.file == FileRole::None);
                if e.kind == ErrorKind::InvalidInput
                    && defaulted
                    && !linked.iter().any(|l| l == socket)
                    && !input_decides.contains(&format!("{ty}.{socket}").as_str())
                {
                    drifted.push(format!("{ty}.{socket}: {e}"));
                }
            }
            other => panic!("{id}: {other:?}"),
        }
    }
    assert!(
        drifted.is_empty(),
        "nodes refusing their own defaults: {drifted:#?}"
    );
    eprintln!("{ran} of {} nodes ran on their defaults", tested.len());
    assert!(
        ran * 2 >= tested.len(),
        "only {ran} of {} nodes ran on their defaults: {:#?}",
        tested.len(),
        rep.errors()
    );
}
