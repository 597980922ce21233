//! Planning a run: which nodes the requested outputs need, which outputs each must produce,
//! and every needed node's cache key (build identity, type, literals, input file stamps,
//! upstream keys, frame for time-dependent nodes, history for stateful nodes, output folder
//! for writers).

use super::RunOptions;
use crate::cache::{stamp_input, Key};
use crate::validate::{InputSource, ValidGraph};
use cgnodes_api::node::{FileEnv, FileRole};
use cgnodes_api::types::Value;
use std::collections::{BTreeSet, HashMap};

/// The nodes a run needs and the outputs each must produce: `None` = all of them (targets,
/// and outputs the caller reads whole); else the sockets linked by needed nodes or read by
/// name.
pub(super) fn wanted_outputs(
    graph: &ValidGraph,
    opts: &RunOptions,
) -> (Vec<bool>, Vec<Option<BTreeSet<String>>>) {
    let targets: Vec<usize> = match &opts.targets {
        Some(t) => t
            .iter()
            .filter_map(|id| graph.index.get(id).copied())
            .collect(),
        None => graph.targets.clone(),
    };
    let n = graph.nodes.len();
    let mut wanted: Vec<Option<BTreeSet<String>>> = vec![Some(BTreeSet::new()); n];
    let mut roots = targets.clone();
    for &t in &targets {
        wanted[t] = None;
    }
    for r in &opts.read_outputs {
        let (id, socket) = match r.split_once('.') {
            Some((id, socket)) => (id, Some(socket)),
            None => (r.as_str(), None),
        };
        let Some(&i) = graph.index.get(id) else {
            continue;
        };
        roots.push(i);
        match (socket, &mut wanted[i]) {
            (None, w) => *w = None,
            (Some(sock), Some(w)) => {
                w.insert(sock.to_string());
            }
            (Some(_), None) => {}
        }
    }
    let need = graph.needed(&roots);
    for (j, node) in graph.nodes.iter().enumerate() {
        if !need[j] {
            continue;
        }
        for (_, src) in &node.inputs {
            if let InputSource::Links(links) = src {
                for (j, out) in links {
                    if let Some(w) = &mut wanted[*j] {
                        w.insert(out.clone());
                    }
                }
            }
        }
    }
    if opts.all_outputs {
        wanted.iter_mut().for_each(|w| *w = None);
    }
    (need, wanted)
}

/// Computes every needed node's cache key in topological order (see `crate::cache` for
/// what a key covers). `history` holds, for each stateful node that holds state, the key
/// it had at the frame that last advanced that state; a stateful node absent from it starts
/// a new history here. Paths that arrive through links are stamped later, when their value
/// is known (`Executor::evaluate`).
pub fn cache_keys(
    graph: &ValidGraph,
    need: &[bool],
    files: &FileEnv,
    frame: i64,
    history: &HashMap<String, Key>,
) -> Vec<Key> {
    let identity = crate::cache::build_identity();
    let mut keys = vec![[0u8; 32]; graph.nodes.len()];
    for (i, node) in graph.nodes.iter().enumerate() {
        if !need[i] {
            continue;
        }
        let d = &node.decl;
        // A writer whose output path names the frame writes a file per frame: it depends on
        // time even when its inputs do not change (a still arm is written every frame).
        let per_frame_file = node.inputs.iter().any(|(name, src)| {
            matches!(src, InputSource::Literal(v) | InputSource::Default(v)
                if d.input(name).is_some_and(|s| s.file == FileRole::Output)
                    && path_strings(v).iter().any(|p| p.contains("{frame")))
        });
        let mut h = blake3::Hasher::new();
        h.update(&identity);
        h.update(d.type_name.as_bytes());
        h.update(b"\0");
        h.update(d.source.as_bytes());
        h.update(b"\0");
        for (name, src) in &node.inputs {
            h.update(name.as_bytes());
            h.update(b"=");
            match src {
                InputSource::Literal(v) | InputSource::Default(v) => {
                    let j = v.to_json().map(|j| j.to_string()).unwrap_or_default();
                    h.update(j.as_bytes());
                    let role = d.input(name).map(|s| s.file).unwrap_or_default();
                    if role == FileRole::Input {
                        for p in path_strings(v) {
                            stamp_input(&mut h, &files.input_path(p), d.companions);
                        }
                    }
                }
                InputSource::Links(ls) => {
                    for (j, out) in ls {
                        h.update(&keys[*j]);
                        h.update(out.as_bytes());
                        h.update(b";");
                    }
                }
                InputSource::Unset => {
                    h.update(b"<unset>");
                }
            }
            h.update(b"\0");
        }
        if d.time_dependent || d.stateful || per_frame_file {
            h.update(b"frame");
            h.update(&frame.to_le_bytes());
        }
        if d.stateful {
            match history.get(&node.id) {
                Some(prev) => {
                    h.update(b"after");
                    h.update(prev);
                }
                None => {
                    h.update(b"origin");
                }
            }
        }
        if d.sink || d.inputs.iter().any(|s| s.file == FileRole::Output) {
            h.update(files.out_dir.to_string_lossy().as_bytes());
            h.update(&[u8::from(files.allow_write_anywhere)]);
        }
        keys[i] = *h.finalize().as_bytes();
    }
    keys
}

/// The files a run of `graph` reads through literal file parameters, resolved as the run
/// resolves them, with their companions (an OBJ's MTL libraries and textures). A path with a
/// `{frame}` pattern gives its folder. `run --watch` and `serve` watch these; files named by
/// links (computed paths) are not known before the run.
pub fn input_files(graph: &ValidGraph, files: &FileEnv) -> Vec<std::path::PathBuf> {
    let mut out = BTreeSet::new();
    for node in &graph.nodes {
        let d = &node.decl;
        for (name, src) in &node.inputs {
            let (InputSource::Literal(v) | InputSource::Default(v)) = src else {
                continue;
            };
            if d.input(name).map(|s| s.file) != Some(FileRole::Input) {
                continue;
            }
            for p in path_strings(v) {
                if p.contains("{frame") {
                    if let Some(dir) = files.input_path(p).parent() {
                        out.insert(dir.to_path_buf());
                    }
                    continue;
                }
                let path = files.input_path(p);
                if let Some(f) = d.companions {
                    out.extend(f(&path));
                }
                out.insert(path);
            }
        }
    }
    out.into_iter().collect()
}

/// The paths a file socket's value names: a string, or each string of a list.
pub(super) fn path_strings(v: &Value) -> Vec<&str> {
    match v {
        Value::String(s) => vec![s.as_str()],
        Value::List(items) => items
            .iter()
            .filter_map(|x| match x {
                Value::String(s) => Some(s.as_str()),
                _ => None,
            })
            .collect(),
        _ => Vec::new(),
    }
}
