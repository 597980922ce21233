//! The node-map table: every Framework3D `id_name` with what it becomes in cgnodes, as
//! `cgnodes import-f3d --list-map [--markdown]` prints it (docs/framework3d.md carries the
//! Markdown version).

use super::NodeMap;
use std::collections::BTreeMap;

/// How a map treats its node, in words: the cgnodes node (and helper nodes), `removed`, or
/// `not run`.
pub fn kind(m: &NodeMap) -> String {
    if m.unsupported.is_some() {
        return "not run (warning)".into();
    }
    let Some(t) = &m.node_type else {
        return "removed".into();
    };
    let mut helpers: Vec<&str> = m
        .inputs
        .values()
        .chain(m.outputs.values())
        .flatten()
        .filter_map(|t| t.split_once(['<', '>']))
        .filter_map(|(_, h)| h.split_once('.').map(|(ty, _)| ty))
        .chain(
            m.feeds
                .values()
                .filter_map(|f| f.split_once(':').map(|p| p.0)),
        )
        .collect();
    helpers.sort();
    helpers.dedup();
    if helpers.is_empty() {
        format!("`{t}`")
    } else {
        let h: Vec<String> = helpers.iter().map(|h| format!("`{h}`")).collect();
        format!("`{t}` (+ {})", h.join(", "))
    }
}

/// The family of an `id_name`: geometry, function, composition or render.
pub fn family(id_name: &str) -> &'static str {
    match id_name.split('_').next() {
        Some("geom") => "geometry",
        Some("func") => "function",
        Some("comp") => "composition",
        Some("render") => "render",
        _ => "other",
    }
}

/// One line per map: `id_name`, family, cgnodes node, note or reason; as a Markdown table
/// when `markdown`, else tab-separated.
pub fn map_table(maps: &BTreeMap<String, NodeMap>, markdown: bool) -> String {
    let mut rows: Vec<(&str, &String, &NodeMap)> =
        maps.iter().map(|(k, m)| (family(k), k, m)).collect();
    rows.sort_by_key(|r| (r.0, r.1.to_ascii_lowercase()));
    let mut out = String::new();
    if markdown {
        out.push_str("| Framework3D node | family | cgnodes | note |\n|---|---|---|---|\n");
    }
    for (fam, id, m) in rows {
        let note = m.unsupported.as_deref().or(m.note.as_deref()).unwrap_or("");
        if markdown {
            out.push_str(&format!(
                "| `{id}` | {fam} | {} | {} |\n",
                kind(m),
                note.replace('|', "\\|")
            ));
        } else {
            out.push_str(&format!(
                "{id}\t{fam}\t{}\t{note}\n",
                kind(m).replace('`', "")
            ));
        }
    }
    out
}
