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

/// Applies `--set NODE.SOCKET=VALUE` overrides to a graph's literals. The value is read as
/// JSON when it parses, else as a string, and checked later by validation against the
/// socket's type.
pub fn apply_sets(g: &mut Graph, sets: &[String]) -> Result<(), String> {
    for s in sets {
        let (lhs, val) = s
            .split_once('=')
            .ok_or_else(|| format!("--set '{s}': expected NODE.SOCKET=VALUE"))?;
        let (node, socket) =
            split_link(lhs).ok_or_else(|| format!("--set '{s}': expected NODE.SOCKET=VALUE"))?;
        if !g.spec.nodes.contains_key(node) {
            let hint = closest(node, g.spec.nodes.keys().map(String::as_str))
                .map(|h| format!(" (did you mean '{h}'?)"))
                .unwrap_or_default();
            return Err(format!("--set '{s}': no node '{node}' in the graph{hint}"));
        }
        let Some(spec) = g.spec.nodes.get_mut(node) else {
            continue;
        };
        if spec.inputs.contains_key(socket) {
            return Err(format!("--set '{s}': input '{socket}' of node '{node}' is linked; a literal cannot replace a link"));
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
