//! `cgnodes._native`: the pyo3 side of the Python package. It loads, validates and runs a
//! graph with the GIL released and hands the outputs back as plain Python objects; arrays
//! travel as `{"__array__": bytes, "dtype": ..., "shape": ...}` dicts, which the pure-Python
//! layer (`python/cgnodes/__init__.py`) turns into numpy arrays with `numpy.frombuffer`, so
//! this crate needs no numpy bindings.

use cgnodes::exec::{Executor, NodeStatus, RunOptions};
use cgnodes::graph::{self, apply_sets};
use cgnodes::node::FileEnv;
use cgnodes::registry::Registry;
use cgnodes::types::{Attribute, AttributeData, Domain, Image, Mesh, Points, Table, Value};
use cgnodes::validate::validate_needed;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

/// The built-in node registry, assembled once per process.
fn registry() -> &'static Registry {
    static R: OnceLock<Registry> = OnceLock::new();
    R.get_or_init(cgnodes::nodes::builtin_registry)
}

/// What went wrong, in a shape the Python layer turns into `GraphError` or `NodeError`.
enum Failure {
    /// The graph could not be loaded, overridden or validated: (node, message) per problem.
    Graph(Vec<(Option<String>, String)>),
    /// The run failed: one entry per failed node.
    Nodes(Vec<NodeFailure>),
}

struct NodeFailure {
    node: String,
    node_type: String,
    socket: Option<String>,
    kind: String,
    message: String,
}

/// What a successful run hands back: outputs by node id, plus logs and written files.
struct Outputs {
    values: BTreeMap<String, Arc<BTreeMap<String, Value>>>,
    logs: Vec<(String, String)>,
    written: Vec<PathBuf>,
}

/// The arguments of one run, owned so the run can happen without the GIL.
struct Job {
    source: String,
    is_path: bool,
    base_dir: PathBuf,
    sets: Vec<String>,
    targets: Option<Vec<String>>,
    out: PathBuf,
    frame: i64,
    assets: Vec<PathBuf>,
}

fn graph_problem(msg: impl Into<String>) -> Failure {
    Failure::Graph(vec![(None, msg.into())])
}

/// Loads, validates and runs a graph: the whole job, without touching Python.
fn run_job(job: &Job) -> Result<Outputs, Failure> {
    let reg = registry();
    let aliases = Default::default();
    let mut g = if job.is_path {
        graph::load_with(Path::new(&job.source), &aliases, reg)
    } else {
        graph::parse_with(
            &job.source,
            Path::new("<dict>"),
            &job.base_dir,
            &aliases,
            reg,
        )
    }
    .map_err(|e| graph_problem(e.to_string()))?;
    apply_sets(&mut g, &job.sets).map_err(|e| graph_problem(e.to_string()))?;
    if let Some(ts) = &job.targets {
        for t in ts {
            if !g.spec.nodes.contains_key(t) {
                return Err(graph_problem(format!(
                    "target '{t}' is not a node of {}",
                    g.file.display()
                )));
            }
        }
    }
    let (valid, _warnings) = validate_needed(&g, reg, &job.assets, job.targets.as_deref())
        .map_err(|errs| {
            Failure::Graph(
                errs.iter()
                    .map(|e| (e.node().map(str::to_string), e.to_string()))
                    .collect(),
            )
        })?;
    let exec = Executor::new(None, None).map_err(|e| graph_problem(e.to_string()))?;
    let read: Vec<String> = match &job.targets {
        Some(t) => t.clone(),
        None => valid
            .targets
            .iter()
            .map(|&i| valid.nodes[i].id.clone())
            .collect(),
    };
    let opts = RunOptions {
        targets: job.targets.clone(),
        files: FileEnv {
            graph_dir: valid.dir.clone(),
            asset_dirs: job.assets.clone(),
            out_dir: job.out.clone(),
            allow_write_anywhere: false,
        },
        read_outputs: read.clone(),
        ..Default::default()
    };
    let report = exec.run(&valid, &opts, job.frame);
    let failures: Vec<NodeFailure> = report
        .nodes
        .iter()
        .filter_map(|n| match &n.status {
            NodeStatus::Failed(e) => Some(NodeFailure {
                node: n.id.clone(),
                node_type: n.node_type.clone(),
                socket: e.socket.clone(),
                kind: e.kind.to_string(),
                message: e.message.clone(),
            }),
            _ => None,
        })
        .collect();
    if !failures.is_empty() {
        return Err(Failure::Nodes(failures));
    }
    let values = read
        .iter()
        .filter_map(|id| report.outputs.get(id).map(|o| (id.clone(), o.clone())))
        .collect();
    Ok(Outputs {
        values,
        logs: report
            .nodes
            .iter()
            .flat_map(|n| n.logs.iter().map(|l| (n.id.clone(), l.clone())))
            .collect(),
        written: report
            .nodes
            .iter()
            .flat_map(|n| n.written.clone())
            .collect(),
    })
}

/// An array for the Python layer: raw little-endian bytes, a numpy dtype string and a shape.
fn array<'py>(
    py: Python<'py>,
    bytes: &[u8],
    dtype: &str,
    shape: &[usize],
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("__array__", PyBytes::new(py, bytes))?;
    d.set_item("dtype", dtype)?;
    d.set_item("shape", shape.to_vec())?;
    Ok(d)
}

fn f64_bytes<const N: usize>(v: &[[f64; N]]) -> Vec<u8> {
    v.iter()
        .flat_map(|p| p.iter().flat_map(|x| x.to_le_bytes()))
        .collect()
}

fn f64s<'py, const N: usize>(py: Python<'py>, v: &[[f64; N]]) -> PyResult<Bound<'py, PyDict>> {
    array(py, &f64_bytes(v), "<f8", &[v.len(), N])
}

fn domain_name(d: Domain) -> &'static str {
    match d {
        Domain::Vertex => "vertex",
        Domain::Corner => "corner",
        Domain::Face => "face",
    }
}

/// Sets `name` (an (n, N) float64 array) and `name_domain` from a mesh attribute.
fn set_attr<const N: usize>(
    d: &Bound<'_, PyDict>,
    name: &str,
    a: &Attribute<[f64; N]>,
) -> PyResult<()> {
    d.set_item(name, f64s(d.py(), &a.values)?)?;
    d.set_item(format!("{name}_domain"), domain_name(a.domain))
}

/// A mesh as a dict: `positions` (n, 3) float64; `faces` (m, 3) uint32 for a triangle mesh,
/// else `face_counts` and `face_indices`; `uvs`, `normals`, `colors` with their domains when
/// present; named attributes under `attributes`.
fn mesh<'py>(py: Python<'py>, m: &Mesh) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("positions", f64s(py, &m.positions)?)?;
    let u32s = |v: &[u32]| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
    match m.triangles() {
        Some(t) if m.is_triangle_mesh() => {
            let flat: Vec<u32> = t.iter().flatten().copied().collect();
            d.set_item("faces", array(py, &u32s(&flat), "<u4", &[t.len(), 3])?)?;
        }
        _ => {}
    }
    let counts = m.face_counts();
    let idx = m.face_indices();
    d.set_item(
        "face_counts",
        array(py, &u32s(counts), "<u4", &[counts.len()])?,
    )?;
    d.set_item("face_indices", array(py, &u32s(idx), "<u4", &[idx.len()])?)?;
    if let Some(a) = &m.uvs {
        set_attr(&d, "uvs", a)?;
    }
    if let Some(a) = &m.normals {
        set_attr(&d, "normals", a)?;
    }
    if let Some(a) = &m.colors {
        set_attr(&d, "colors", a)?;
    }
    let attrs = PyDict::new(py);
    for (name, a) in &m.attributes {
        let v = match a {
            AttributeData::Float(a) => {
                let b: Vec<u8> = a.values.iter().flat_map(|x| x.to_le_bytes()).collect();
                array(py, &b, "<f8", &[a.values.len()])?
            }
            AttributeData::Vec2(a) => f64s(py, &a.values)?,
            AttributeData::Vec3(a) => f64s(py, &a.values)?,
            AttributeData::Int(a) => {
                let b: Vec<u8> = a.values.iter().flat_map(|x| x.to_le_bytes()).collect();
                array(py, &b, "<i8", &[a.values.len()])?
            }
        };
        attrs.set_item(name, v)?;
    }
    d.set_item("attributes", attrs)?;
    Ok(d)
}

/// An image as a (height, width, 4) float32 RGBA array, row 0 at the top.
fn image<'py>(py: Python<'py>, im: &Image) -> PyResult<Bound<'py, PyDict>> {
    let b: Vec<u8> = im
        .pixels
        .iter()
        .flat_map(|p| p.iter().flat_map(|x| x.to_le_bytes()))
        .collect();
    array(py, &b, "<f4", &[im.height as usize, im.width as usize, 4])
}

/// A table as `{"__table__": {column: [values]}, "meta": {...}}`.
fn table<'py>(py: Python<'py>, t: &Table) -> PyResult<Bound<'py, PyDict>> {
    let cols = PyDict::new(py);
    for (name, v) in &t.columns {
        cols.set_item(name, v.clone())?;
    }
    let d = PyDict::new(py);
    d.set_item("__table__", cols)?;
    d.set_item("meta", t.meta.clone())?;
    Ok(d)
}

fn points<'py>(py: Python<'py>, p: &Points) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("dim", p.dim)?;
    d.set_item("positions", f64s(py, &p.positions)?)?;
    for (k, v) in &p.scalars {
        let b: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        d.set_item(k, array(py, &b, "<f8", &[v.len()])?)?;
    }
    for (k, v) in &p.vectors {
        d.set_item(k, f64s(py, v)?)?;
    }
    Ok(d)
}

/// Any other serializable value as `{"__json__": text}` (cameras, lights, materials, scenes,
/// skeletons, models), which the Python layer parses with `json.loads`.
fn as_json<'py, T: serde::Serialize>(py: Python<'py>, v: &T) -> PyResult<Bound<'py, PyAny>> {
    let d = PyDict::new(py);
    d.set_item("__json__", serde_json::to_string(v).unwrap_or_default())?;
    Ok(d.into_any())
}

fn value<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Int(i) => i.into_pyobject(py)?.into_any(),
        Value::Float(f) => f.into_pyobject(py)?.into_any(),
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Vec2(a) => a.to_vec().into_pyobject(py)?.into_any(),
        Value::Vec3(a) | Value::Color(a) => a.to_vec().into_pyobject(py)?.into_any(),
        Value::Mesh(m) => mesh(py, m)?.into_any(),
        Value::Image(im) => image(py, im)?.into_any(),
        Value::Points(p) => points(py, p)?.into_any(),
        Value::Table(t) => table(py, t)?.into_any(),
        Value::Curve(c) => {
            let d = PyDict::new(py);
            d.set_item("points", f64s(py, &c.points)?)?;
            d.set_item("closed", c.closed)?;
            d.into_any()
        }
        Value::Camera(x) => as_json(py, &**x)?,
        Value::Light(x) => as_json(py, &**x)?,
        Value::Material(x) => as_json(py, &**x)?,
        Value::Scene(x) => as_json(py, &**x)?,
        Value::Skeleton(x) => as_json(py, &**x)?,
        Value::Model(x) => as_json(py, &**x)?,
        Value::List(items) => {
            let l = PyList::empty(py);
            for it in items.iter() {
                l.append(value(py, it)?)?;
            }
            l.into_any()
        }
    })
}

/// Runs a graph (a file path, or graph JSON text when `is_path` is false) for one frame.
/// Returns `{"ok": True, "outputs": {node: {socket: value}}, "logs": [...], "written": [...]}`
/// or `{"ok": False, "graph_errors": [(node, message)]}` / `{"ok": False, "node_errors":
/// [{node, node_type, socket, kind, message}]}`; the Python layer raises the exceptions.
#[pyfunction]
#[pyo3(signature = (source, is_path, base_dir, sets, targets, out, frame, assets))]
#[allow(clippy::too_many_arguments)]
fn run<'py>(
    py: Python<'py>,
    source: String,
    is_path: bool,
    base_dir: String,
    sets: Vec<String>,
    targets: Option<Vec<String>>,
    out: String,
    frame: i64,
    assets: Vec<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let job = Job {
        source,
        is_path,
        base_dir: base_dir.into(),
        sets,
        targets,
        out: out.into(),
        frame,
        assets: assets.into_iter().map(PathBuf::from).collect(),
    };
    let result = py.detach(|| run_job(&job));
    let d = PyDict::new(py);
    match result {
        Ok(o) => {
            d.set_item("ok", true)?;
            let outs = PyDict::new(py);
            for (id, sockets) in &o.values {
                let s = PyDict::new(py);
                for (name, v) in sockets.iter() {
                    s.set_item(name, value(py, v)?)?;
                }
                outs.set_item(id, s)?;
            }
            d.set_item("outputs", outs)?;
            d.set_item("logs", o.logs)?;
            let written: Vec<String> = o.written.iter().map(|p| p.display().to_string()).collect();
            d.set_item("written", written)?;
        }
        Err(Failure::Graph(errs)) => {
            d.set_item("ok", false)?;
            d.set_item("graph_errors", errs)?;
        }
        Err(Failure::Nodes(fs)) => {
            d.set_item("ok", false)?;
            let l = PyList::empty(py);
            for f in fs {
                let e = PyDict::new(py);
                e.set_item("node", f.node)?;
                e.set_item("node_type", f.node_type)?;
                e.set_item("socket", f.socket)?;
                e.set_item("kind", f.kind)?;
                e.set_item("message", f.message)?;
                l.append(e)?;
            }
            d.set_item("node_errors", l)?;
        }
    }
    Ok(d)
}

/// The built-in node type names, sorted.
#[pyfunction]
fn nodes() -> Vec<String> {
    let mut v: Vec<String> = registry().iter().map(|d| d.type_name.clone()).collect();
    v.sort();
    v
}

/// One node type's declaration as JSON text (doc, category, inputs and outputs with types,
/// defaults, ranges and choices), or `None` for an unknown type.
#[pyfunction]
fn describe(node_type: &str) -> Option<String> {
    registry()
        .get(node_type)
        .and_then(|d| serde_json::to_string(&**d).ok())
}

/// The closest known node type name to `name`, for "did you mean" hints.
#[pyfunction]
fn closest(name: &str) -> Option<String> {
    registry().closest(name)
}

/// The cgnodes version this module was built from.
#[pyfunction]
fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(nodes, m)?)?;
    m.add_function(wrap_pyfunction!(describe, m)?)?;
    m.add_function(wrap_pyfunction!(closest, m)?)?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    Ok(())
}
