//! Running one node: blocks it when an upstream node failed, completes its key with the
//! stamps of files named through links, serves it from the caches when its key is unchanged, else gathers its inputs, runs it (catching panics), checks its
//! outputs against the declaration and stores the result.

use super::{Executor, Failed, NodeReport, NodeStatus, Shared};
use crate::cache::{stamp_input, Entry, Key};
use crate::validate::InputSource;
use cgnodes_api::node::{ErrorKind, ExecContext, FileRole, NodeDecl, NodeError, RunSetup};
use cgnodes_api::types::{SocketType, Value};
use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;

/// Outputs by socket name, shared with the nodes that read them.
type Outputs = Arc<BTreeMap<String, Value>>;

impl Executor {
    /// Gathers inputs, consults the caches, runs the node and checks its outputs. Fails with
    /// the node that failed: an upstream one that blocks this node, or this node.
    pub(super) fn evaluate(
        &self,
        sh: &Shared,
        i: usize,
        report: &mut NodeReport,
    ) -> Result<Outputs, Failed> {
        let node = &sh.graph.nodes[i];
        if let Some(failed) = blocked_by(sh, i) {
            report.status = NodeStatus::Blocked {
                by: failed.0.clone(),
            };
            return Err(failed);
        }
        let key = complete_key(sh, i);
        let _ = sh.final_keys[i].set(key);
        let wanted = sh.wanted[i].as_ref();
        // A cached entry that skipped an output wanted now is kept, to merge with the rerun.
        let mut older = None;
        if !node.decl.stateful && !sh.fresh[i] {
            if let Some(e) = self.lookup(&key) {
                if e.serves(wanted) {
                    report.status = NodeStatus::Cached;
                    report.written = e.written.clone();
                    return Ok(e.outputs);
                }
                older = Some(e);
            }
        }
        let ran = gather_inputs(sh, i)
            .and_then(|inputs| self.execute(sh, i, inputs, key, report))
            .and_then(|outputs| {
                let skipped = check_outputs(&node.decl, &outputs, wanted)?;
                Ok((outputs, skipped))
            });
        let (outputs, skipped) = match ran {
            Ok(r) => r,
            Err(e) => {
                report.status = NodeStatus::Failed(e);
                return Err(Failed(node.id.clone()));
            }
        };
        let mut e = Entry {
            outputs: Arc::new(outputs),
            written: report.written.clone(),
            skipped,
        };
        if let Some(older) = &older {
            e = e.merged_with(older);
        }
        let outputs = e.outputs.clone();
        if !node.decl.stateful {
            self.store(key, e);
        }
        Ok(outputs)
    }

    /// Runs node `i` on `inputs` (catching panics), with its state taken out while it runs
    /// and put back after; the logs and written files go into `report`.
    fn execute(
        &self,
        sh: &Shared,
        i: usize,
        inputs: BTreeMap<String, Value>,
        key: Key,
        report: &mut NodeReport,
    ) -> Result<BTreeMap<String, Value>, NodeError> {
        let node = &sh.graph.nodes[i];
        let decl = &node.decl;
        let mut state = if decl.stateful {
            self.states
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .remove(&node.id)
        } else {
            None
        };
        let Some(exec) = decl.exec.clone() else {
            return Err(NodeError::new(
                ErrorKind::Internal,
                "node has no implementation",
            ));
        };
        let setup = RunSetup {
            inputs,
            frame: sh.frame,
            state: &mut state,
            files: &sh.opts.files,
            progress: sh.opts.progress.clone(),
            log_sink: sh.opts.log.clone(),
            wanted: sh.wanted[i].clone(),
            memory_limit: sh.opts.memory_limit(),
            provenance: Some(Arc::new(provenance(sh, node))),
        };
        let mut ctx = ExecContext::for_run(&node.id, decl, setup);
        let res = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| exec(&mut ctx)));
        // Ends the node's progress bar, if it started one, whether it succeeded or not.
        ctx.progress(1.0);
        let done = ctx.finish();
        report.logs = done.logs;
        report.written = done.written;
        report.written_values = done.written_values;
        drop(ctx);
        if decl.stateful {
            self.keep_state(&node.id, state, key);
        }
        match res {
            Ok(Ok(())) => Ok(done.outputs),
            Ok(Err(e)) => Err(e),
            Err(panic) => {
                let msg = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                Err(NodeError::new(
                    ErrorKind::Internal,
                    format!("the node panicked: {msg}"),
                ))
            }
        }
    }

    /// Puts a stateful node's state back after it ran. The history follows the state: the
    /// next frame's key chains onto this one while the node holds state, and starts anew
    /// when it dropped it.
    fn keep_state(&self, id: &str, state: Option<Box<dyn std::any::Any + Send>>, key: Key) {
        // Locked in the order the planner locks them.
        let mut states = self.states.lock().unwrap_or_else(|p| p.into_inner());
        let mut hist = self.histories.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(s) = state {
            states.insert(id.to_string(), s);
            hist.insert(id.to_string(), key);
        } else {
            hist.remove(id);
        }
    }

    /// Stores a node's result in the memory cache and, when there is one, the disk cache.
    fn store(&self, key: Key, e: Entry) {
        if let Some(d) = &self.disk {
            d.put(&key, &e);
        }
        self.memory
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .put(key, e);
    }

    fn lookup(&self, key: &Key) -> Option<Entry> {
        let hit = self
            .memory
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .get(key);
        let hit = hit.or_else(|| {
            let e = self.disk.as_ref()?.get(key)?;
            self.memory
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .put(*key, e.clone());
            Some(e)
        });
        hit.filter(|e| e.files_present())
    }
}

/// The upstream node whose failure blocks node `i`, if any.
fn blocked_by(sh: &Shared, i: usize) -> Option<Failed> {
    sh.graph.nodes[i].deps.iter().find_map(|&d| {
        match sh.slots[d]
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .as_ref()
        {
            Some(Err(failed)) => Some(failed.clone()),
            _ => None,
        }
    })
}

/// Node `i`'s inputs, each converted to its socket's type; linked values get the range and
/// choice check validation gave literals.
fn gather_inputs(sh: &Shared, i: usize) -> Result<BTreeMap<String, Value>, NodeError> {
    let node = &sh.graph.nodes[i];
    let mut inputs = BTreeMap::new();
    for (name, src) in &node.inputs {
        let Some(sdecl) = node.decl.input(name) else {
            continue;
        };
        let v = match src {
            InputSource::Literal(v) | InputSource::Default(v) => v.clone(),
            InputSource::Unset => continue,
            InputSource::Links(links) => linked_value(sh, name, &sdecl.ty, links)?,
        };
        let Some(v) = v.convert_to(&sdecl.ty) else {
            return Err(NodeError::invalid(
                name,
                format!("cannot convert {} to {}", v.socket_type(), sdecl.ty),
            ));
        };
        // Validation checked literals against the declared range and choices; a linked
        // value arrives only now and gets the same check (issue 23).
        if matches!(src, InputSource::Links(_)) {
            sdecl
                .check_literal(&v)
                .map_err(|msg| NodeError::invalid(name, msg))?;
        }
        inputs.insert(name.clone(), v);
    }
    Ok(inputs)
}

/// The value input `name` of type `ty` gets through `links`: a list input gets every linked
/// value (lists flattened), another input the last.
fn linked_value(
    sh: &Shared,
    name: &str,
    ty: &SocketType,
    links: &[(usize, String)],
) -> Result<Value, NodeError> {
    let mut vals = Vec::new();
    for (j, out) in links {
        let slot = sh.slots[*j].lock().unwrap_or_else(|p| p.into_inner());
        let v = slot
            .as_ref()
            .and_then(|r| r.as_ref().ok())
            .and_then(|o| o.get(out))
            .cloned();
        let Some(v) = v else {
            return Err(NodeError::new(
                ErrorKind::Internal,
                format!("'{}' produced no output '{out}'", sh.graph.nodes[*j].id),
            )
            .at(name));
        };
        vals.push(v);
    }
    if !matches!(ty, SocketType::List(_)) {
        return Ok(vals.pop().unwrap_or(Value::Bool(false)));
    }
    let mut flat = Vec::new();
    for v in vals {
        match v {
            Value::List(items) => flat.extend(items.iter().cloned()),
            other => flat.push(other),
        }
    }
    Ok(Value::List(Arc::new(flat)))
}

/// Checks a node's outputs against its declaration: every output it must give is there and
/// of its type. Returns the outputs skipped because no one wanted them.
fn check_outputs(
    decl: &NodeDecl,
    outputs: &BTreeMap<String, Value>,
    wanted: Option<&BTreeSet<String>>,
) -> Result<Vec<String>, NodeError> {
    let is_wanted = |name: &str| wanted.is_none_or(|w| w.contains(name));
    let mut skipped = Vec::new();
    for o in &decl.outputs {
        match outputs.get(&o.name) {
            None if !is_wanted(&o.name) => skipped.push(o.name.clone()),
            None if o.optional => {}
            None => {
                return Err(NodeError::new(
                    ErrorKind::Internal,
                    format!("produced no output '{}'", o.name),
                ))
            }
            Some(v)
                if !o.ty.accepts(&v.socket_type())
                    && !matches!(v, Value::List(l) if l.is_empty()) =>
            {
                return Err(NodeError::new(
                    ErrorKind::Internal,
                    format!(
                        "output '{}' should be {} but is {}",
                        o.name,
                        o.ty,
                        v.socket_type()
                    ),
                ));
            }
            _ => {}
        }
    }
    Ok(skipped)
}

/// The node's key completed at evaluation time: the planned key, plus the completed keys of
/// upstream nodes whose keys changed, plus the stamp (and companions) of every file named by
/// a path that arrives through a link. Equal to the planned key when there is neither.
fn complete_key(sh: &Shared, i: usize) -> Key {
    let node = &sh.graph.nodes[i];
    let decl = &node.decl;
    let mut h: Option<blake3::Hasher> = None;
    for &d in &node.deps {
        let k = sh.final_keys[d].get().copied().unwrap_or(sh.keys[d]);
        if k != sh.keys[d] {
            let h = h.get_or_insert_with(blake3::Hasher::new);
            h.update(&(d as u64).to_le_bytes());
            h.update(&k);
        }
    }
    for (name, src) in &node.inputs {
        let InputSource::Links(links) = src else {
            continue;
        };
        if decl.input(name).map(|s| s.file) != Some(FileRole::Input) {
            continue;
        }
        for (j, out) in links {
            let slot = sh.slots[*j].lock().unwrap_or_else(|p| p.into_inner());
            let Some(v) = slot
                .as_ref()
                .and_then(|r| r.as_ref().ok())
                .and_then(|o| o.get(out))
            else {
                continue;
            };
            let h = h.get_or_insert_with(blake3::Hasher::new);
            h.update(name.as_bytes());
            h.update(b"=");
            for p in super::plan::path_strings(v) {
                stamp_input(h, &sh.opts.files.input_path(p), decl.companions);
            }
        }
    }
    match h {
        None => sh.keys[i],
        Some(mut h) => {
            h.update(b"planned");
            h.update(&sh.keys[i]);
            *h.finalize().as_bytes()
        }
    }
}

/// What the files `node` writes record: this build, the graph's hash, the node and its
/// literal parameters, the frame.
fn provenance(sh: &Shared, node: &crate::validate::ValidNode) -> cgnodes_api::node::Provenance {
    let params = node
        .inputs
        .iter()
        .filter_map(|(name, src)| match src {
            InputSource::Literal(v) => Some((name.clone(), v.to_json()?)),
            _ => None,
        })
        .collect();
    cgnodes_api::node::Provenance {
        cgnodes: env!("CARGO_PKG_VERSION").to_string(),
        graph: sh.graph.file.display().to_string(),
        graph_hash: sh.graph.hash.clone(),
        node: node.id.clone(),
        node_type: node.decl.type_name.clone(),
        params,
        frame: sh.frame,
    }
}
