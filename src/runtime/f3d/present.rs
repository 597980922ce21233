//! What `render_present` shows when the passes before it are not run: the nearest node
//! upstream (through the Framework3D links) that was imported and has a `color` output,
//! so a project renders a frame before every pass has a cgnodes counterpart.

use super::util::{f3d_id, short_name, sockets_in_order};
use crate::graph::format::{GraphFile, LinkSpec};
use cgnodes_api::registry::Registry;
use std::collections::{BTreeMap, BTreeSet, VecDeque};

/// For every imported `render_present` whose `image` is not linked (its source was not
/// run), links the `color` output of the nearest imported node upstream. Returns one
/// warning per fallback, naming the nodes skipped over; a present with nothing upstream
/// to show is left alone.
pub fn link_present_fallback(
    raw: &serde_json::Value,
    spec: &mut GraphFile,
    registry: &Registry,
) -> Vec<String> {
    let mut warnings = Vec::new();
    let Some(nodes) = raw.get("nodes_info").and_then(|v| v.as_object()) else {
        return warnings;
    };
    // node id -> (id_name, input sockets); output socket -> node id; input socket -> source.
    let mut info: BTreeMap<i64, (String, Vec<i64>)> = BTreeMap::new();
    let mut owner: BTreeMap<i64, i64> = BTreeMap::new();
    for (k, n) in nodes {
        let Ok(id) = f3d_id(k, n, "node") else {
            continue;
        };
        let name = n.get("id_name").and_then(|v| v.as_str()).unwrap_or("");
        info.insert(id, (name.to_string(), sockets_in_order(n.get("inputs"))));
        for s in sockets_in_order(n.get("outputs")) {
            owner.insert(s, id);
        }
    }
    let mut source: BTreeMap<i64, i64> = BTreeMap::new();
    if let Some(links) = raw.get("links_info").and_then(|v| v.as_object()) {
        for l in links.values() {
            if let (Some(a), Some(b)) = (
                l.get("StartPinID").and_then(|v| v.as_i64()),
                l.get("EndPinID").and_then(|v| v.as_i64()),
            ) {
                source.insert(b, a);
            }
        }
    }
    let cg_id = |id: i64| format!("{}_{id}", short_name(&info[&id].0));
    let has_color = |spec: &GraphFile, id: &str| {
        spec.nodes
            .get(id)
            .and_then(|n| registry.get(&n.node_type))
            .is_some_and(|d| d.outputs.iter().any(|o| o.name == "color"))
    };
    let presents: Vec<i64> = info
        .iter()
        .filter(|(_, (n, _))| n == "render_present")
        .map(|(id, _)| *id)
        .collect();
    for p in presents {
        let pid = cg_id(p);
        let unlinked = spec
            .nodes
            .get(&pid)
            .is_some_and(|n| !n.inputs.contains_key("image"));
        if !unlinked {
            continue;
        }
        let mut queue = VecDeque::from([p]);
        let mut seen = BTreeSet::from([p]);
        let mut skipped = Vec::new();
        let mut found = None;
        'search: while let Some(n) = queue.pop_front() {
            for s in &info[&n].1 {
                let Some(m) = source.get(s).and_then(|s| owner.get(s)).copied() else {
                    continue;
                };
                if !seen.insert(m) {
                    continue;
                }
                let mid = cg_id(m);
                if has_color(spec, &mid) {
                    found = Some((m, mid));
                    break 'search;
                }
                if !spec.nodes.contains_key(&mid) {
                    skipped.push(format!("{} (node {m})", info[&m].0));
                }
                queue.push_back(m);
            }
        }
        if let Some((m, mid)) = found {
            if let Some(n) = spec.nodes.get_mut(&pid) {
                n.inputs
                    .insert("image".into(), LinkSpec::One(format!("{mid}.color")));
            }
            warnings.push(format!(
                "render_present (node {p}) shows the colour of {} (node {m}) instead: {} not run",
                info[&m].0,
                if skipped.is_empty() {
                    "the pass it was linked to is".to_string()
                } else {
                    format!("{} are", skipped.join(", "))
                }
            ));
        }
    }
    warnings
}
