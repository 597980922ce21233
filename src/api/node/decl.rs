//! Node declarations: a node type's sockets (names, types, defaults, ranges, choices, file
//! roles), its documentation and how it behaves over frames, plus its execution function.

use crate::types::{SocketType, Value};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

use super::{ExecContext, NodeError};

/// The function that runs a node.
pub type ExecFn = Arc<dyn Fn(&mut ExecContext) -> Result<(), NodeError> + Send + Sync>;

/// What a file-path socket is for, so the runtime can resolve and guard it.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum FileRole {
    /// Not a path.
    #[default]
    None,
    /// A file the node reads (resolved against the graph's folder; its stamp enters the cache key).
    Input,
    /// A file the node writes (resolved under the output directory).
    Output,
}

/// One socket of a node declaration.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
pub struct SocketDecl {
    /// Socket name (snake_case).
    pub name: String,
    /// Socket type.
    #[serde(rename = "type")]
    pub ty: SocketType,
    /// One-line description.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub doc: String,
    /// Default literal used when the graph gives neither a literal nor a link.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub default: Option<serde_json::Value>,
    /// Smallest accepted number (Int and Float sockets).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<f64>,
    /// Largest accepted number (Int and Float sockets).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<f64>,
    /// Accepted strings (enum parameters).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub choices: Option<Vec<String>>,
    /// Whether the input may be left unconnected with no default.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub optional: bool,
    /// Whether the socket names a file to read or write.
    #[serde(default, skip_serializing_if = "is_none_role")]
    pub file: FileRole,
}

fn is_none_role(r: &FileRole) -> bool {
    *r == FileRole::None
}

impl SocketDecl {
    /// Checks a literal against range and choices; `Err` says what is wrong.
    pub fn check_literal(&self, v: &Value) -> Result<(), String> {
        let num = match v {
            Value::Int(i) => Some(*i as f64),
            Value::Float(f) => Some(*f),
            _ => None,
        };
        if let Some(x) = num {
            // A NaN compares false against both bounds, so it is refused explicitly.
            if x.is_nan() && (self.min.is_some() || self.max.is_some()) {
                return Err("NaN is outside every range".to_string());
            }
            if let Some(lo) = self.min {
                if x < lo {
                    return Err(format!("{x} is below the minimum {lo}"));
                }
            }
            if let Some(hi) = self.max {
                if x > hi {
                    return Err(format!("{x} is above the maximum {hi}"));
                }
            }
        }
        if let (Some(choices), Value::String(s)) = (&self.choices, v) {
            if !choices.iter().any(|c| c == s) {
                return Err(format!("'{s}' is not one of {}", choices.join(", ")));
            }
        }
        Ok(())
    }

    /// The default as a value of the socket's type.
    pub fn default_value(&self) -> Option<Value> {
        self.default
            .as_ref()
            .and_then(|j| Value::from_json(&self.ty, j).ok())
    }
}

/// The declaration of a node type: sockets, documentation and how it behaves over time.
#[derive(Clone, Serialize, Deserialize, schemars::JsonSchema)]
pub struct NodeDecl {
    /// Node type name (snake_case).
    #[serde(rename = "type")]
    pub type_name: String,
    /// One-line description.
    #[serde(default)]
    pub doc: String,
    /// Domain the node belongs to (for listings).
    #[serde(default)]
    pub category: String,
    /// Input sockets (literals in `params` or links in `inputs`).
    #[serde(default)]
    pub inputs: Vec<SocketDecl>,
    /// Output sockets.
    #[serde(default)]
    pub outputs: Vec<SocketDecl>,
    /// Keeps state between frames (simulations); runs every frame.
    #[serde(default)]
    pub stateful: bool,
    /// Depends on the frame number even without state.
    #[serde(default)]
    pub time_dependent: bool,
    /// Writes files or prints: evaluated by default, never skipped as unused.
    #[serde(default)]
    pub sink: bool,
    /// Where the node comes from: `builtin`, a crate name, or a plugin folder.
    #[serde(default)]
    pub source: String,
    /// The function that runs the node.
    #[serde(skip)]
    #[schemars(skip)]
    pub exec: Option<ExecFn>,
    /// Lists the further files the node reads because of each of its input files (an OBJ's
    /// MTL libraries and textures): they are stamped in the cache key with the input file.
    #[serde(skip)]
    #[schemars(skip)]
    pub companions: Option<CompanionFn>,
}

impl std::fmt::Debug for NodeDecl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NodeDecl")
            .field("type", &self.type_name)
            .finish_non_exhaustive()
    }
}

impl NodeDecl {
    /// The input socket called `name`.
    pub fn input(&self, name: &str) -> Option<&SocketDecl> {
        self.inputs.iter().find(|s| s.name == name)
    }

    /// The output socket called `name`.
    pub fn output(&self, name: &str) -> Option<&SocketDecl> {
        self.outputs.iter().find(|s| s.name == name)
    }

    /// Checks values given to this node's inputs against their declared ranges and choices,
    /// as the runtime does before a node runs, so that a node's `execute` never re-checks
    /// them; for callers that run a node outside a graph (`ExecContext::standalone`).
    pub fn check_inputs<'v>(
        &self,
        inputs: impl IntoIterator<Item = (&'v String, &'v Value)>,
    ) -> Result<(), NodeError> {
        for (name, v) in inputs {
            if let Some(s) = self.input(name) {
                let v = v.convert_to(&s.ty).unwrap_or_else(|| v.clone());
                s.check_literal(&v)
                    .map_err(|msg| NodeError::invalid(name, msg))?;
            }
        }
        Ok(())
    }
}

/// Lists the other files a node reads because it reads `path` (for example an OBJ's MTL
/// libraries and textures), so that the cache key covers them; named in `companions`.
pub type CompanionFn = fn(&std::path::Path) -> Vec<std::path::PathBuf>;

#[cfg(test)]
mod tests {
    use super::*;

    fn ranged(min: Option<f64>, max: Option<f64>) -> SocketDecl {
        SocketDecl {
            name: "ambient".into(),
            ty: SocketType::Float,
            doc: String::new(),
            default: None,
            min,
            max,
            choices: None,
            optional: false,
            file: FileRole::None,
        }
    }

    /// A NaN (a linked value computed as 0/0, say) is refused by any range, as an infinity
    /// beyond it is, and an unranged socket still takes it.
    #[test]
    fn nan_is_outside_every_range() {
        let s = ranged(Some(0.0), Some(1e3));
        assert!(s
            .check_literal(&Value::Float(f64::NAN))
            .unwrap_err()
            .contains("NaN"));
        assert!(s.check_literal(&Value::Float(f64::INFINITY)).is_err());
        assert!(s.check_literal(&Value::Float(0.5)).is_ok());
        assert!(ranged(None, Some(1.0))
            .check_literal(&Value::Float(f64::NAN))
            .is_err());
        assert!(ranged(None, None)
            .check_literal(&Value::Float(f64::NAN))
            .is_ok());
    }
}
