//! Small parsers shared by the importer: socket targets, helper specs, widget values.

use super::ImportError;
use cgnodes_api::types::SocketType;

/// Splits a feed spec `type:out`.
pub(super) fn feed(spec: &str) -> Result<(&str, &str), ImportError> {
    spec.split_once(':')
        .ok_or_else(|| ImportError(format!("feed '{spec}' should read 'type:output'")))
}

/// A widget value as the text `NodeMap::values` keys it by: integers without a fraction
/// (`1.0` -> `1`), other numbers as Rust prints them, strings as they are.
pub(super) fn value_key(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Number(n) => match n.as_f64() {
            Some(x) if x.fract() == 0.0 && x.abs() < 1e15 => format!("{}", x as i64),
            Some(x) => format!("{x}"),
            None => n.to_string(),
        },
        serde_json::Value::Bool(b) => (if *b { "1" } else { "0" }).to_string(),
        serde_json::Value::String(t) => t.clone(),
        other => other.to_string(),
    }
}

/// A target `socket[k]`: component `k` of a vector socket, as (`socket`, `k`).
pub(super) fn component(target: &str) -> Option<(&str, usize)> {
    let (base, rest) = target.split_once('[')?;
    let k = rest.strip_suffix(']')?.parse().ok()?;
    Some((base, k))
}

/// Splits a helper spec `type.in:out`.
pub(super) fn helper(spec: &str) -> Result<(&str, &str, &str), ImportError> {
    let bad = || ImportError(format!("helper '{spec}' should read 'type.input:output'"));
    let (t, rest) = spec.split_once('.').ok_or_else(bad)?;
    let (i, o) = rest.split_once(':').ok_or_else(bad)?;
    Ok((t, i, o))
}

pub(super) fn sockets_in_order(v: Option<&serde_json::Value>) -> Vec<i64> {
    let mut s: Vec<(i64, i64)> = v
        .and_then(|v| v.as_object())
        .map(|o| {
            o.iter()
                .filter_map(|(k, id)| Some((k.parse().ok()?, id.as_i64()?)))
                .collect()
        })
        .unwrap_or_default();
    // keys "0","1",...,"10" are sorted as strings in the file: order by number
    s.sort();
    s.into_iter().map(|(_, id)| id).collect()
}

pub(super) fn short_name(id_name: &str) -> &str {
    id_name
        .strip_prefix("geom_")
        .or_else(|| id_name.strip_prefix("func_"))
        .unwrap_or(id_name)
}

/// A literal for socket `decl` from a Framework3D widget value.
pub(super) fn literal(v: &serde_json::Value, ty: Option<&SocketType>) -> Option<serde_json::Value> {
    use serde_json::json;
    Some(match (ty, v) {
        (Some(SocketType::Bool), serde_json::Value::Number(n)) => json!(n.as_f64()? != 0.0),
        (Some(SocketType::Int), serde_json::Value::Number(n)) => json!(n.as_f64()?.round() as i64),
        (Some(SocketType::Float), serde_json::Value::Number(n)) => json!(n.as_f64()?),
        (Some(SocketType::String), serde_json::Value::Number(n)) => json!(n.to_string()),
        _ => v.clone(),
    })
}

/// The `ID` of a Framework3D socket or node, else its key in the file.
pub(super) fn f3d_id(key: &str, v: &serde_json::Value, what: &str) -> Result<i64, ImportError> {
    v.get("ID")
        .and_then(|v| v.as_i64())
        .or_else(|| key.parse().ok())
        .ok_or_else(|| ImportError(format!("{what} '{key}' has no ID")))
}
