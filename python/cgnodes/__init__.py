"""Run cgnodes graphs from Python.

    import cgnodes
    out = cgnodes.run("graphs/arap_cow.json", set={"arap.iterations": 5}, targets=["arap"])
    V = out["arap"]["mesh"]["positions"]      # (n, 3) float64 numpy array

Meshes come back as dicts of numpy arrays (``positions`` (n, 3), ``faces`` (m, 3) for
triangle meshes, always ``face_counts`` + ``face_indices``, ``uvs``/``normals``/``colors``
with their ``*_domain`` when present, named ``attributes``); images as float32 arrays of
shape (height, width, 4) (RGBA, linear, row 0 at the top); tables as a pandas DataFrame when
pandas imports, else a dict of lists; numbers, strings and vectors as plain Python values.
The graph runs in Rust with the GIL released.
"""

import json
import os
import tempfile

import numpy as np

from . import _native

__all__ = ["run", "nodes", "describe", "NodeError", "GraphError", "__version__"]
__version__ = _native.version()


class GraphError(ValueError):
    """The graph could not be loaded or validated (or ``set=``/``targets=`` name nothing).

    ``errors`` lists every problem as ``(node or None, message)``; ``node`` is the first
    problem's node."""

    def __init__(self, errors):
        self.errors = [(n, m) for n, m in errors]
        self.node = self.errors[0][0] if self.errors else None
        self.message = "\n".join(m for _, m in self.errors)
        super().__init__(self.message)


class NodeError(RuntimeError):
    """A node failed while running. ``node`` (id), ``node_type``, ``socket`` (the input at
    fault, or None), ``kind`` (invalid_input, topology, singular, ...) and ``message`` come
    from the first failed node; ``failures`` lists every failed node as dicts."""

    def __init__(self, failures):
        self.failures = failures
        first = failures[0]
        self.node = first["node"]
        self.node_type = first["node_type"]
        self.socket = first["socket"]
        self.kind = first["kind"]
        self.message = first["message"]
        where = f"socket '{self.socket}': " if self.socket else ""
        super().__init__(f"node '{self.node}' ({self.node_type}): {where}{self.message}")


def _table(cols):
    try:
        import pandas as pd
    except ImportError:
        return cols
    return pd.DataFrame(cols)


def _convert(v):
    """Turns the native layer's encoded values into numpy arrays, DataFrames and dicts."""
    if isinstance(v, dict):
        if "__array__" in v:
            a = np.frombuffer(v["__array__"], dtype=np.dtype(v["dtype"]))
            return a.reshape(tuple(v["shape"]))
        if "__table__" in v:
            return _table({k: list(c) for k, c in v["__table__"].items()})
        if "__json__" in v:
            return json.loads(v["__json__"])
        return {k: _convert(x) for k, x in v.items()}
    if isinstance(v, list):
        return [_convert(x) for x in v]
    return v


def run(graph, set=None, targets=None, out=None, frame=0, assets=None, base_dir=None):
    """Runs a graph for one frame and returns ``{node_id: {output_socket: value}}`` for
    ``targets`` (node ids; default: the graph's ``outputs``, else its sinks).

    graph: a path to a graph JSON file, or the graph as a dict (relative paths in a dict
      graph resolve against ``base_dir``, default the current folder).
    set: ``{"node.socket": value}`` literal overrides, as ``cgnodes run --set``.
    out: folder for the files writer nodes write; None writes them into a temporary folder
      that is removed after the run.
    frame: the frame to evaluate. assets: further folders searched for input files.

    Raises GraphError for a graph that does not load or validate and NodeError when a node
    fails (with its node id, type and socket)."""
    if isinstance(graph, dict):
        # Canonical JSON: the provenance hash of a dict graph does not depend on key order.
        source = json.dumps(graph, sort_keys=True, separators=(",", ":"))
        is_path = False
    else:
        source = os.fspath(graph)
        is_path = True
    sets = [f"{k}={json.dumps(v)}" for k, v in (set or {}).items()]
    if isinstance(targets, str):
        targets = [targets]
    args = dict(
        source=source,
        is_path=is_path,
        base_dir=os.fspath(base_dir or os.getcwd()),
        sets=sets,
        targets=list(targets) if targets is not None else None,
        frame=int(frame),
        assets=[os.fspath(a) for a in (assets or [])],
    )
    if out is None:
        with tempfile.TemporaryDirectory(prefix="cgnodes-") as tmp:
            r = _native.run(out=tmp, **args)
    else:
        r = _native.run(out=os.fspath(out), **args)
    if not r["ok"]:
        if "graph_errors" in r:
            raise GraphError(r["graph_errors"])
        raise NodeError(r["node_errors"])
    return {node: _convert(sockets) for node, sockets in r["outputs"].items()}


def nodes():
    """The built-in node type names, sorted."""
    return _native.nodes()


def describe(node_type):
    """One node type's declaration as a dict: ``type``, ``doc``, ``category``, ``inputs``
    and ``outputs`` (each socket a dict with ``name``, ``type``, ``doc`` and, when set,
    ``default``, ``min``, ``max``, ``choices``, ``optional``, ``file``), and the flags
    ``stateful``, ``time_dependent``, ``sink``. Raises KeyError for an unknown type."""
    text = _native.describe(node_type)
    if text is None:
        hint = _native.closest(node_type)
        raise KeyError(
            f"unknown node type '{node_type}'" + (f" (did you mean '{hint}'?)" if hint else "")
        )
    return json.loads(text)
