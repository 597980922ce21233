//! Plugin manifests: reading and checking `cgnodes-plugin.json`, and turning its node
//! declarations into registrable nodes that run the plugin's command.

use super::call::{execute, Runner};
use super::{codec, DEFAULT_TIMEOUT_S, MANIFEST, PROTOCOL, TIMEOUT_SOCKET};
use cgnodes_api::node::{ExecContext, FileRole, NodeDecl, SocketDecl};
use cgnodes_api::types::{SocketType, Value};
use serde::Deserialize;
use serde_json::json;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Why a plugin's manifest could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum ManifestError {
    /// The manifest could not be read.
    #[error("{}: {source}", .file.display())]
    Read {
        /// The manifest file.
        file: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// The manifest is not JSON of the manifest's schema.
    #[error("{}: {source}", .file.display())]
    Json {
        /// The manifest file.
        file: PathBuf,
        /// The parser's error.
        source: serde_json::Error,
    },
    /// The plugin folder has no absolute path.
    #[error("{}: {source}", .dir.display())]
    Folder {
        /// The plugin folder.
        dir: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// The manifest parses but declares something cgnodes refuses.
    #[error("{}: {problem}", .file.display())]
    Invalid {
        /// The manifest file.
        file: PathBuf,
        /// What it declares wrong.
        problem: Box<ManifestProblem>,
    },
}

/// What a parsed manifest declares wrong.
#[derive(Debug, thiserror::Error)]
pub enum ManifestProblem {
    /// Another protocol version.
    #[error("plugin '{name}' speaks protocol {protocol}, this cgnodes speaks {PROTOCOL}")]
    Protocol {
        /// The plugin's name.
        name: String,
        /// The protocol it speaks.
        protocol: u32,
    },
    /// A plugin name that is not snake_case.
    #[error("plugin name '{0}' should be snake_case letters, digits and '_'")]
    Name(String),
    /// No program to run.
    #[error("'command' is empty")]
    EmptyCommand,
    /// A time limit that is not a positive number.
    #[error("'timeout' must be a positive number of seconds, got {0}")]
    Timeout(f64),
    /// A node declaration cgnodes refuses.
    #[error("node '{node}': {problem}")]
    Node {
        /// The node's type name.
        node: String,
        /// What is wrong with it.
        problem: DeclProblem,
    },
}

/// What a plugin's node declaration declares wrong; `side` is `input` or `output`.
#[derive(Debug, thiserror::Error)]
pub enum DeclProblem {
    /// A type name that is not snake_case.
    #[error("the type name should be snake_case letters, digits and '_'")]
    TypeName,
    /// A socket name that is not snake_case.
    #[error("{side} '{name}': socket names are snake_case")]
    SocketName {
        /// `input` or `output`.
        side: &'static str,
        /// The socket.
        name: String,
    },
    /// A socket declared twice on one side.
    #[error("{side} '{name}' is declared twice")]
    Twice {
        /// `input` or `output`.
        side: &'static str,
        /// The socket.
        name: String,
    },
    /// A socket type the protocol cannot carry (scenes).
    #[error("{side} '{name}': {ty} values cannot cross the plugin boundary")]
    Unsupported {
        /// `input` or `output`.
        side: &'static str,
        /// The socket.
        name: String,
        /// Its type.
        ty: SocketType,
    },
    /// A default that is not a valid literal of the socket.
    #[error("{side} '{name}': default: {message}")]
    Default {
        /// `input` or `output`.
        side: &'static str,
        /// The socket.
        name: String,
        /// The literal check's message.
        message: String,
    },
    /// A file role on a socket that is not a string.
    #[error("{side} '{name}': only string sockets name files")]
    FileRole {
        /// `input` or `output`.
        side: &'static str,
        /// The socket.
        name: String,
    },
    /// A `timeout` input that is not a float.
    #[error("input '{TIMEOUT_SOCKET}' is the call's time limit and must be a float")]
    TimeoutType,
}

/// A plugin manifest (`cgnodes-plugin.json`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// Plugin name.
    pub name: String,
    /// Plugin version (free text; part of the nodes' cache key).
    #[serde(default)]
    pub version: String,
    /// One-line description.
    #[serde(default)]
    pub doc: String,
    /// The protocol version the plugin speaks (1).
    pub protocol: u32,
    /// The program and its arguments. A program given with a `/` is relative to the plugin
    /// folder; a bare name (`python3`) is looked up in `PATH`. The command runs in the plugin
    /// folder.
    pub command: Vec<String>,
    /// Default time limit per call in seconds.
    #[serde(default)]
    pub timeout: Option<f64>,
    /// The nodes, in the schema `cgnodes nodes --json` prints.
    pub nodes: Vec<NodeDecl>,
}

/// A loaded plugin: where it lives, how to run it, and its node declarations.
#[derive(Clone, Debug)]
pub struct Plugin {
    /// Plugin name.
    pub name: String,
    /// Plugin version.
    pub version: String,
    /// The plugin folder (absolute).
    pub dir: PathBuf,
    /// The resolved command.
    pub argv: Vec<OsString>,
    /// Default time limit per call in seconds.
    pub timeout: f64,
    /// The nodes, ready to register.
    pub nodes: Vec<NodeDecl>,
}

impl Plugin {
    /// What `call` needs to run this plugin's nodes.
    pub fn runner(&self) -> Runner {
        Runner {
            plugin: self.name.clone(),
            dir: self.dir.clone(),
            argv: self.argv.clone(),
            timeout: self.timeout,
        }
    }

    /// The declaration of node `type_name`.
    pub fn node(&self, type_name: &str) -> Option<&NodeDecl> {
        self.nodes.iter().find(|d| d.type_name == type_name)
    }
}

/// Reads and checks the manifest in `dir`; the nodes run the plugin's command.
pub fn load(dir: &Path) -> Result<Plugin, ManifestError> {
    let file = dir.join(MANIFEST);
    let text = std::fs::read_to_string(&file).map_err(|source| ManifestError::Read {
        file: file.clone(),
        source,
    })?;
    let m: Manifest = serde_json::from_str(&text).map_err(|source| ManifestError::Json {
        file: file.clone(),
        source,
    })?;
    let dir = std::path::absolute(dir).map_err(|source| ManifestError::Folder {
        dir: dir.into(),
        source,
    })?;
    let err = |problem: ManifestProblem| ManifestError::Invalid {
        file: file.clone(),
        problem: Box::new(problem),
    };
    if m.protocol != PROTOCOL {
        return Err(err(ManifestProblem::Protocol {
            name: m.name.clone(),
            protocol: m.protocol,
        }));
    }
    if !is_name(&m.name) {
        return Err(err(ManifestProblem::Name(m.name.clone())));
    }
    let Some((prog, args)) = m.command.split_first() else {
        return Err(err(ManifestProblem::EmptyCommand));
    };
    let prog_os: OsString = if prog.contains('/') {
        if Path::new(prog).is_absolute() {
            prog.into()
        } else {
            dir.join(prog).into_os_string()
        }
    } else {
        prog.into()
    };
    let mut argv = vec![prog_os];
    argv.extend(args.iter().map(OsString::from));
    let timeout = m.timeout.unwrap_or(DEFAULT_TIMEOUT_S);
    if !(timeout.is_finite() && timeout > 0.0) {
        return Err(err(ManifestProblem::Timeout(timeout)));
    }
    let runner = Arc::new(Runner {
        plugin: m.name.clone(),
        dir: dir.clone(),
        argv: argv.clone(),
        timeout,
    });
    // The source enters the nodes' cache keys: the stamp makes a changed script miss the
    // disk cache.
    let source = format!(
        "plugin {}{} ({}) #{}",
        m.name,
        if m.version.is_empty() {
            String::new()
        } else {
            format!(" {}", m.version)
        },
        dir.display(),
        folder_stamp(&dir)
    );
    let mut nodes = Vec::new();
    for mut d in m.nodes {
        check_decl(&d).map_err(|problem| {
            err(ManifestProblem::Node {
                node: d.type_name.clone(),
                problem,
            })
        })?;
        bind_node(&mut d, &runner, &source);
        nodes.push(d);
    }
    Ok(Plugin {
        name: m.name,
        version: m.version,
        dir,
        argv,
        timeout,
        nodes,
    })
}

/// Makes a checked declaration runnable: the `timeout` input (unless declared), the
/// plugin's `source` and category, and an `exec` that calls the plugin through `runner`.
fn bind_node(d: &mut NodeDecl, runner: &Arc<Runner>, source: &str) {
    let added_timeout = d.input(TIMEOUT_SOCKET).is_none();
    if added_timeout {
        d.inputs.push(SocketDecl {
            name: TIMEOUT_SOCKET.into(),
            ty: SocketType::Float,
            doc: "Seconds before the plugin process is killed.".into(),
            default: Some(json!(runner.timeout)),
            min: Some(0.001),
            max: None,
            choices: None,
            optional: false,
            file: FileRole::None,
        });
    }
    d.source = source.into();
    if d.category.is_empty() {
        d.category = "plugin".into();
    }
    let r = runner.clone();
    d.exec = Some(Arc::new(move |ctx: &mut ExecContext| {
        execute(&r, added_timeout, ctx)
    }));
}

/// Files and folders of a plugin at most this deep are stamped.
const STAMP_DEPTH: usize = 8;
/// At most this many files of a plugin folder are stamped (in name order).
const STAMP_FILES: usize = 10_000;

/// A short hash of the relative paths, sizes and modification times of the files in a plugin
/// folder and its subfolders (modules, data, binaries it ships): it changes when any of
/// them is edited. Hidden entries (`.git`) and `__pycache__` are left out (Python rewrites
/// them as it runs); at most `STAMP_DEPTH` levels and `STAMP_FILES` files are visited.
fn folder_stamp(dir: &Path) -> String {
    let mut files: Vec<(String, u64, u128)> = Vec::new();
    let mut stack = vec![(dir.to_path_buf(), 0usize)];
    while let Some((d, depth)) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&d) else {
            continue;
        };
        let mut entries: Vec<_> = rd.filter_map(|e| e.ok()).collect();
        entries.sort_by_key(|e| e.file_name());
        for e in entries {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') || name == "__pycache__" || files.len() >= STAMP_FILES {
                continue;
            }
            let Ok(m) = e.metadata() else { continue };
            let rel = e
                .path()
                .strip_prefix(dir)
                .map_or(name.clone(), |p| p.to_string_lossy().into_owned());
            if m.is_dir() {
                if depth + 1 < STAMP_DEPTH {
                    stack.push((e.path(), depth + 1));
                }
            } else if m.is_file() {
                let t = m
                    .modified()
                    .ok()
                    .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
                    .map_or(0, |d| d.as_nanos());
                files.push((rel, m.len(), t));
            }
        }
    }
    files.sort();
    let mut h = blake3::Hasher::new();
    for (name, len, t) in files {
        h.update(name.as_bytes());
        h.update(b"\0");
        h.update(&len.to_le_bytes());
        h.update(&t.to_le_bytes());
    }
    h.finalize().to_hex()[..8].to_string()
}

fn is_name(s: &str) -> bool {
    !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
        && !s.starts_with(|c: char| c.is_ascii_digit())
}

/// Checks a node declaration from a manifest: names, unique sockets, types the protocol
/// carries, defaults of the socket's type.
fn check_decl(d: &NodeDecl) -> Result<(), DeclProblem> {
    if !is_name(&d.type_name) {
        return Err(DeclProblem::TypeName);
    }
    for (side, list) in [("input", &d.inputs), ("output", &d.outputs)] {
        let mut seen = std::collections::BTreeSet::new();
        for s in list.iter() {
            if !is_name(&s.name) {
                return Err(DeclProblem::SocketName {
                    side,
                    name: s.name.clone(),
                });
            }
            if !seen.insert(&s.name) {
                return Err(DeclProblem::Twice {
                    side,
                    name: s.name.clone(),
                });
            }
            if !codec::supported(&s.ty) {
                return Err(DeclProblem::Unsupported {
                    side,
                    name: s.name.clone(),
                    ty: s.ty.clone(),
                });
            }
            if let Some(j) = &s.default {
                let bad_default = |message: String| DeclProblem::Default {
                    side,
                    name: s.name.clone(),
                    message,
                };
                let v = Value::from_json(&s.ty, j).map_err(bad_default)?;
                s.check_literal(&v).map_err(bad_default)?;
            }
            if s.file != FileRole::None && s.ty != SocketType::String {
                return Err(DeclProblem::FileRole {
                    side,
                    name: s.name.clone(),
                });
            }
        }
    }
    if let Some(t) = d.input(TIMEOUT_SOCKET) {
        if t.ty != SocketType::Float {
            return Err(DeclProblem::TimeoutType);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn manifests_are_checked() {
        let d = tempfile::tempdir().unwrap();
        let write = |text: &str| std::fs::write(d.path().join(MANIFEST), text).unwrap();
        write(r#"{"name": "p", "protocol": 2, "command": ["x"], "nodes": []}"#);
        assert!(load(d.path())
            .unwrap_err()
            .to_string()
            .contains("protocol 2"));
        write(r#"{"name": "p", "protocol": 1, "command": [], "nodes": []}"#);
        assert!(load(d.path()).unwrap_err().to_string().contains("empty"));
        write(r#"{"name": "p", "protocol": 1, "command": ["x"], "nodes": [], "shell": "rm"}"#);
        assert!(load(d.path())
            .unwrap_err()
            .to_string()
            .contains("unknown field"));
        write(
            r#"{"name": "p", "protocol": 1, "command": ["x"], "nodes": [
               {"type": "n", "inputs": [{"name": "s", "type": "scene"}]}]}"#,
        );
        assert!(load(d.path())
            .unwrap_err()
            .to_string()
            .contains("cannot cross"));
        write(
            r#"{"name": "p", "protocol": 1, "command": ["x"], "nodes": [
               {"type": "n", "inputs": [{"name": "k", "type": "int", "default": 2.5}]}]}"#,
        );
        assert!(load(d.path()).unwrap_err().to_string().contains("default"));
        write(
            r#"{"name": "p", "protocol": 1, "command": ["bin/run"], "timeout": 5, "nodes": [
               {"type": "n", "inputs": [{"name": "k", "type": "int", "default": 2}],
                "outputs": [{"name": "v", "type": "float"}]}]}"#,
        );
        let p = load(d.path()).unwrap();
        assert!(Path::new(&p.argv[0]).is_absolute());
        let n = &p.nodes[0];
        assert!(n.source.starts_with("plugin p ("));
        let t = n.input(TIMEOUT_SOCKET).unwrap();
        assert_eq!(t.default, Some(json!(5.0)));
    }

    #[test]
    fn the_stamp_covers_subfolders_but_not_python_caches() {
        let d = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(d.path().join("lib/deep")).unwrap();
        std::fs::create_dir_all(d.path().join("__pycache__")).unwrap();
        std::fs::write(d.path().join("run.py"), "import lib").unwrap();
        std::fs::write(d.path().join("lib/deep/m.py"), "X = 1").unwrap();
        let s0 = folder_stamp(d.path());
        std::fs::write(d.path().join("__pycache__/m.pyc"), "bytecode").unwrap();
        std::fs::write(d.path().join(".hidden"), "x").unwrap();
        assert_eq!(folder_stamp(d.path()), s0);
        // A module two folders down changes (size differs): the stamp changes.
        std::fs::write(d.path().join("lib/deep/m.py"), "X = 22").unwrap();
        assert_ne!(folder_stamp(d.path()), s0);
    }
}
