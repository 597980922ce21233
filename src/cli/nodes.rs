//! `cgnodes nodes`: every node type with its sockets, as text or as JSON declarations.

use crate::node::SocketDecl;
use crate::registry::Registry;

/// `cgnodes nodes [--json]`.
pub(super) fn cmd(registry: &Registry, json: bool) -> i32 {
    if json {
        let all: Vec<_> = registry.iter().map(|d| d.as_ref().clone()).collect();
        println!("{}", serde_json::to_string_pretty(&all).unwrap_or_default());
    } else {
        for d in registry.iter() {
            let src = if d.source == "builtin" {
                String::new()
            } else {
                format!("  [{}]", d.source)
            };
            println!("{:<24} {}{src}", d.type_name, d.doc);
            println!("{:<24}   in:  {}", "", sockets(&d.inputs));
            println!("{:<24}   out: {}", "", sockets(&d.outputs));
        }
    }
    0
}

fn sockets(s: &[SocketDecl]) -> String {
    s.iter()
        .map(|s| format!("{}: {}", s.name, s.ty))
        .collect::<Vec<_>>()
        .join(", ")
}
