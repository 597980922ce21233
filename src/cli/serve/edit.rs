//! Setting one parameter in a graph file's text, leaving every other byte as it was: a change
//! made on the page is a one-line diff of the user's own file (key order, spacing and
//! comments-free formatting kept), not a re-serialized document.

use serde_json::Value;

/// Why a parameter could not be set in the text.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum EditError {
    /// The text is not JSON this scanner can follow (the loader's error says more).
    #[error("the graph file is not valid JSON at byte {0}")]
    Syntax(usize),
    /// The file is not a cgnodes graph (a Framework3D file is read, not edited).
    #[error("only a cgnodes graph file (\"format\": \"cgnodes-graph\") can be edited here")]
    NotAGraph,
    /// No node with this id in `nodes`.
    #[error("no node '{0}' in the graph file")]
    NoNode(String),
    /// The edited text did not read back with the value set (a bug; nothing is written).
    #[error("the edit of '{node}.{socket}' did not read back")]
    ReadBack {
        /// Node id.
        node: String,
        /// Parameter.
        socket: String,
    },
}

/// A byte range `[start, end)` of the text.
type Span = (usize, usize);

/// An object's members (key, value span) and the position of its closing brace.
struct Object {
    members: Vec<(String, Span)>,
    close: usize,
}

/// Returns `text` with `nodes.<node>.params.<socket>` set to `value`: the old value's bytes
/// replaced, or the member added after the last one (a `params` object added to the node
/// when it has none).
pub fn set_param(text: &str, node: &str, socket: &str, value: &Value) -> Result<String, EditError> {
    let b = text.as_bytes();
    let root = object_at(b, skip_ws(b, 0))?;
    let format = member(&root, "format").map(|s| &text[s.0..s.1]);
    if format != Some("\"cgnodes-graph\"") {
        return Err(EditError::NotAGraph);
    }
    let nodes = member(&root, "nodes").ok_or(EditError::NotAGraph)?;
    let nodes = object_at(b, nodes.0)?;
    let n = member(&nodes, node).ok_or_else(|| EditError::NoNode(node.into()))?;
    let n = object_at(b, n.0)?;
    let v = serde_json::to_string(value).unwrap_or_else(|_| "null".into());
    let key = serde_json::to_string(socket).unwrap_or_default();
    let out = match member(&n, "params") {
        Some(p) => {
            let p = object_at(b, p.0)?;
            match member(&p, socket) {
                Some((s, e)) => splice(text, (s, e), &v),
                None => insert_member(text, &p, &format!("{key}: {v}")),
            }
        }
        None => insert_member(text, &n, &format!("\"params\": {{{key}: {v}}}")),
    };
    // The edit must read back as JSON with the value in place.
    let back: Value = serde_json::from_str(&out).map_err(|_| EditError::ReadBack {
        node: node.into(),
        socket: socket.into(),
    })?;
    if back["nodes"][node]["params"][socket] != *value {
        return Err(EditError::ReadBack {
            node: node.into(),
            socket: socket.into(),
        });
    }
    Ok(out)
}

fn splice(text: &str, (s, e): Span, with: &str) -> String {
    format!("{}{}{}", &text[..s], with, &text[e..])
}

/// Adds `member` to object `o`: after its last member, or inside its empty braces.
fn insert_member(text: &str, o: &Object, member: &str) -> String {
    match o.members.last() {
        Some((_, (_, end))) => splice(text, (*end, *end), &format!(", {member}")),
        None => splice(text, (o.close, o.close), member),
    }
}

fn member(o: &Object, key: &str) -> Option<Span> {
    o.members.iter().find(|(k, _)| k == key).map(|(_, s)| *s)
}

fn skip_ws(b: &[u8], mut i: usize) -> usize {
    while i < b.len() && matches!(b[i], b' ' | b'\t' | b'\n' | b'\r') {
        i += 1;
    }
    i
}

/// The object starting at `i` (which must be `{`).
fn object_at(b: &[u8], i: usize) -> Result<Object, EditError> {
    if b.get(i) != Some(&b'{') {
        return Err(EditError::Syntax(i));
    }
    let mut members = Vec::new();
    let mut j = skip_ws(b, i + 1);
    if b.get(j) == Some(&b'}') {
        return Ok(Object { members, close: j });
    }
    loop {
        let (ks, ke) = value_span(b, j)?;
        if b[ks] != b'"' {
            return Err(EditError::Syntax(ks));
        }
        let key: String = serde_json::from_slice(&b[ks..ke]).map_err(|_| EditError::Syntax(ks))?;
        j = skip_ws(b, ke);
        if b.get(j) != Some(&b':') {
            return Err(EditError::Syntax(j));
        }
        let span = value_span(b, skip_ws(b, j + 1))?;
        members.push((key, span));
        j = skip_ws(b, span.1);
        match b.get(j) {
            Some(b',') => j = skip_ws(b, j + 1),
            Some(b'}') => return Ok(Object { members, close: j }),
            _ => return Err(EditError::Syntax(j)),
        }
    }
}

/// The span of the JSON value starting at `i`.
fn value_span(b: &[u8], i: usize) -> Result<Span, EditError> {
    match b.get(i) {
        Some(b'"') => {
            let mut j = i + 1;
            while j < b.len() {
                match b[j] {
                    b'\\' => j += 2,
                    b'"' => return Ok((i, j + 1)),
                    _ => j += 1,
                }
            }
            Err(EditError::Syntax(i))
        }
        Some(b'{') | Some(b'[') => {
            // Brackets are matched outside strings.
            let mut depth = 0usize;
            let mut j = i;
            while j < b.len() {
                match b[j] {
                    b'"' => {
                        j = value_span(b, j)?.1;
                        continue;
                    }
                    b'{' | b'[' => depth += 1,
                    b'}' | b']' => {
                        depth -= 1;
                        if depth == 0 {
                            return Ok((i, j + 1));
                        }
                    }
                    _ => {}
                }
                j += 1;
            }
            Err(EditError::Syntax(i))
        }
        Some(_) => {
            let mut j = i;
            while j < b.len() && !matches!(b[j], b',' | b'}' | b']' | b' ' | b'\t' | b'\n' | b'\r')
            {
                j += 1;
            }
            if j == i {
                Err(EditError::Syntax(i))
            } else {
                Ok((i, j))
            }
        }
        None => Err(EditError::Syntax(i)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    const G: &str = r#"{
  "format": "cgnodes-graph",
  "version": 1,
  "nodes": {
    "load": {"type": "mesh_load", "params": {"path": "a \"b\" {c}.obj"}},
    "tutte": {
      "type": "tutte",
      "params": {
        "weights": "cotangent",
        "boundary": "circle"
      },
      "inputs": {"mesh": "load.mesh"}
    },
    "bare": {"type": "grid"},
    "empty": {"type": "grid", "params": {}}
  }
}"#;

    #[test]
    fn a_present_value_is_replaced_and_nothing_else_changes() {
        let out = set_param(G, "tutte", "weights", &json!("uniform")).unwrap();
        assert_eq!(out, G.replace("\"cotangent\"", "\"uniform\""));
    }

    #[test]
    fn a_missing_parameter_is_added_after_the_last_one() {
        let out = set_param(G, "tutte", "spacing", &json!("uniform")).unwrap();
        assert!(out.contains("\"boundary\": \"circle\", \"spacing\": \"uniform\"\n"));
        let out = set_param(G, "empty", "size", &json!(2.5)).unwrap();
        assert!(out.contains("\"params\": {\"size\": 2.5}}"));
        let out = set_param(G, "bare", "size", &json!([1, 2])).unwrap();
        assert!(out.contains("{\"type\": \"grid\", \"params\": {\"size\": [1,2]}}"));
        // Strings with quotes and braces inside do not confuse the scanner.
        let out = set_param(G, "load", "path", &json!("x.obj")).unwrap();
        assert!(out.contains("\"params\": {\"path\": \"x.obj\"}}"));
    }

    #[test]
    fn unknown_nodes_other_formats_and_broken_text_are_errors() {
        assert_eq!(
            set_param(G, "nope", "a", &json!(1)),
            Err(EditError::NoNode("nope".into()))
        );
        assert_eq!(
            set_param(r#"{"nodes": {}}"#, "a", "b", &json!(1)),
            Err(EditError::NotAGraph)
        );
        assert!(matches!(
            set_param(&G[..G.len() - 40], "empty", "a", &json!(1)),
            Err(EditError::Syntax(_))
        ));
    }
}
