//! `cgnodes describe NODE_TYPE`: one node type's doc, flags and sockets.

use super::EXIT_USAGE;
use crate::node::NodeDecl;
use crate::registry::Registry;

/// `cgnodes describe NODE_TYPE`; an unknown name gets a "did you mean" hint.
pub(super) fn cmd(registry: &Registry, node_type: &str) -> i32 {
    match registry.get(node_type) {
        Some(d) => {
            print!("{}", describe(d));
            0
        }
        None => {
            let hint = registry
                .closest(node_type)
                .map(|s| format!(" (did you mean '{s}'?)"))
                .unwrap_or_default();
            eprintln!("error: unknown node type '{node_type}'{hint}");
            EXIT_USAGE
        }
    }
}

/// A human description of a node type: doc, then sockets with defaults, ranges and choices.
pub fn describe(d: &NodeDecl) -> String {
    let mut s = format!("{} — {}\n", d.type_name, d.doc);
    if d.source != "builtin" {
        s.push_str(&format!("from: {}\n", d.source));
    }
    let mut flags = Vec::new();
    if d.stateful {
        flags.push("stateful (keeps state between frames)");
    } else if d.time_dependent {
        flags.push("depends on the frame");
    }
    if d.sink {
        flags.push("sink (evaluated by default)");
    }
    if !flags.is_empty() {
        s.push_str(&format!("{}\n", flags.join(", ")));
    }
    for (title, list) in [("inputs", &d.inputs), ("outputs", &d.outputs)] {
        s.push_str(&format!("{title}:\n"));
        for x in list.iter() {
            let mut extra = Vec::new();
            if let Some(v) = &x.default {
                extra.push(format!("default {v}"));
            }
            match (x.min, x.max) {
                (Some(a), Some(b)) => extra.push(format!("range {a}..{b}")),
                (Some(a), None) => extra.push(format!(">= {a}")),
                (None, Some(b)) => extra.push(format!("<= {b}")),
                _ => {}
            }
            if let Some(c) = &x.choices {
                extra.push(format!("one of {}", c.join(" | ")));
            }
            if x.optional {
                extra.push("optional".into());
            }
            let extra = if extra.is_empty() {
                String::new()
            } else {
                format!(" [{}]", extra.join("; "))
            };
            s.push_str(&format!(
                "  {:<16} {:<12} {}{extra}\n",
                x.name,
                x.ty.to_string(),
                x.doc
            ));
        }
    }
    s
}
