//! What the command line (or a sweep) changes in a loaded graph before it runs: `--set`
//! literal overrides and the `--frames A..B` range (with the graph's own `meta.frames` hint).

use super::format::{split_link, Graph, GraphFile};
use cgnodes_api::registry::closest;

impl GraphFile {
    /// The frame range the graph suggests in `meta.frames` (`"A..B"`), used when the command
    /// line gives no `--frames`.
    pub fn frames_hint(&self) -> Option<(i64, i64)> {
        let f = self.meta.as_ref()?.get("frames")?.as_str()?;
        parse_frames(f).ok()
    }
}

/// Parses `A..B` (inclusive) or a single frame `A`.
pub fn parse_frames(s: &str) -> Result<(i64, i64), String> {
    let (a, b) = match s.split_once("..") {
        Some((a, b)) => (a, b.trim_start_matches('=')),
        None => (s, s),
    };
    let a: i64 = a
        .trim()
        .parse()
        .map_err(|_| format!("--frames '{s}': expected A..B"))?;
    let b: i64 = b
        .trim()
        .parse()
        .map_err(|_| format!("--frames '{s}': expected A..B"))?;
    if b < a {
        return Err(format!(
            "--frames '{s}': the last frame comes before the first"
        ));
    }
    Ok((a, b))
}

/// Why a `--set NODE.SOCKET=VALUE` override does not apply to a graph.
#[derive(Debug, thiserror::Error)]
pub enum SetError {
    /// Not of the form `NODE.SOCKET=VALUE`.
    #[error("--set '{0}': expected NODE.SOCKET=VALUE")]
    Syntax(String),
    /// The node is not in the graph; `hint` suggests the closest id.
    #[error("--set '{set}': no node '{node}' in the graph{hint}")]
    NoNode {
        /// The override as given.
        set: String,
        /// The node id.
        node: String,
        /// ` (did you mean 'ID'?)` or empty.
        hint: String,
    },
    /// The socket is linked: a literal cannot replace the link.
    #[error("--set '{set}': input '{socket}' of node '{node}' is linked; a literal cannot replace a link")]
    Linked {
        /// The override as given.
        set: String,
        /// The node id.
        node: String,
        /// The input socket.
        socket: String,
    },
}

/// Applies `--set NODE.SOCKET=VALUE` overrides to a graph's literals. The value is read as
/// JSON when it parses, else as a string, and checked later by validation against the
/// socket's type.
pub fn apply_sets(g: &mut Graph, sets: &[String]) -> Result<(), SetError> {
    for s in sets {
        let syntax = || SetError::Syntax(s.clone());
        let (lhs, val) = s.split_once('=').ok_or_else(syntax)?;
        let (node, socket) = split_link(lhs).ok_or_else(syntax)?;
        if !g.spec.nodes.contains_key(node) {
            let hint = closest(node, g.spec.nodes.keys().map(String::as_str))
                .map(|h| format!(" (did you mean '{h}'?)"))
                .unwrap_or_default();
            return Err(SetError::NoNode {
                set: s.clone(),
                node: node.into(),
                hint,
            });
        }
        let Some(spec) = g.spec.nodes.get_mut(node) else {
            continue;
        };
        if spec.inputs.contains_key(socket) {
            return Err(SetError::Linked {
                set: s.clone(),
                node: node.into(),
                socket: socket.into(),
            });
        }
        let j = serde_json::from_str(val)
            .unwrap_or_else(|_| serde_json::Value::String(val.to_string()));
        spec.params.insert(socket.to_string(), j);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::parse_frames;

    #[test]
    fn frame_ranges() {
        assert_eq!(parse_frames("0..9"), Ok((0, 9)));
        assert_eq!(parse_frames("2..=4"), Ok((2, 4)));
        assert_eq!(parse_frames("5"), Ok((5, 5)));
        assert!(parse_frames("3..1").is_err());
        assert!(parse_frames("a..b").is_err());
    }
}
