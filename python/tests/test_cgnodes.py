"""Tests of the cgnodes Python package (run by .ci/run after `maturin build`).

Each test checks the returned objects against references computed here: closed forms,
the PNG header, the graph's own declarations, or the files the run wrote."""

import math
import os
import struct
from pathlib import Path

import numpy as np
import pytest

import cgnodes

ROOT = Path(__file__).resolve().parents[2]
GRAPHS = ROOT / "graphs"
ASSETS = ROOT / "assets"


def graph(nodes, outputs=None):
    g = {"format": "cgnodes-graph", "version": 1, "nodes": nodes}
    if outputs:
        g["outputs"] = outputs
    return g


def test_example_graph_runs_and_set_overrides_a_parameter():
    r = cgnodes.run(GRAPHS / "arithmetic.json", targets=["pi_r2"])
    assert r["pi_r2"]["value"] == pytest.approx(math.pi * 2.0**2, rel=1e-15)
    r = cgnodes.run(GRAPHS / "arithmetic.json", targets="pi_r2", set={"radius.value": 3.0})
    assert r["pi_r2"]["value"] == pytest.approx(math.pi * 9.0, rel=1e-15)


def test_default_targets_are_the_graph_outputs_and_out_keeps_written_files(tmp_path):
    r = cgnodes.run(GRAPHS / "arithmetic.json", out=tmp_path)
    # The graph names no outputs: its sinks (print, table_write) run, and they have no outputs.
    assert set(r) <= {"show", "save"}
    text = (tmp_path / "circle_area.csv").read_text()
    assert f"{math.pi * 4.0}"[:12] in text


def test_triangle_mesh_dict_has_numpy_arrays_of_the_right_shapes():
    g = graph(
        {"grid": {"type": "mesh_grid", "params": {"cells_u": 3, "cells_v": 2, "size": [4.0, 2.0]}}},
        outputs=["grid"],
    )
    m = cgnodes.run(g)["grid"]["mesh"]
    n, f = 4 * 3, 3 * 2 * 2
    assert m["positions"].shape == (n, 3) and m["positions"].dtype == np.float64
    assert m["faces"].shape == (f, 3) and m["faces"].dtype == np.uint32
    assert m["faces"].max() < n
    np.testing.assert_array_equal(m["face_counts"], np.full(f, 3))
    np.testing.assert_array_equal(m["face_indices"], m["faces"].ravel())
    # A 4 x 2 grid centred at the origin in the xy plane.
    np.testing.assert_allclose(m["positions"].min(axis=0), [-2.0, -1.0, 0.0])
    np.testing.assert_allclose(m["positions"].max(axis=0), [2.0, 1.0, 0.0])
    # Triangles cover the rectangle: the areas add up to 4 * 2.
    p = m["positions"][m["faces"]]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum()
    assert area == pytest.approx(8.0, rel=1e-12)


def test_polygon_mesh_has_counts_and_indices_but_no_faces_array():
    g = graph(
        {"grid": {"type": "mesh_grid", "params": {"cells_u": 2, "cells_v": 2, "triangles": False}}},
        outputs=["grid"],
    )
    m = cgnodes.run(g)["grid"]["mesh"]
    assert "faces" not in m
    np.testing.assert_array_equal(m["face_counts"], [4, 4, 4, 4])
    assert m["face_indices"].shape == (16,)


def test_arap_on_an_assets_mesh_returns_uvs_per_vertex():
    r = cgnodes.run(
        GRAPHS / "arap_cow.json", targets=["arap", "metrics"], set={"arap.iterations": 2}
    )
    m = r["arap"]["mesh"]
    n = m["positions"].shape[0]
    assert m["uvs"].shape == (n, 2) and m["uvs_domain"] == "vertex"
    assert np.isfinite(m["uvs"]).all()
    table = r["metrics"]["table"]
    # A DataFrame when pandas is installed, else a dict of lists: both index by column.
    flipped = list(table["flipped"])
    assert flipped == [0.0]  # arap is injective (the graph asks for it)


def png_size(path):
    with open(path, "rb") as f:
        head = f.read(24)
    assert head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR"
    return struct.unpack(">II", head[16:24])


def test_images_are_float32_height_width_4_and_full_rank_svd_reproduces_them():
    path = ASSETS / "images" / "lena_gray128.png"
    w, h = png_size(path)
    g = graph(
        {
            "load": {"type": "image_load", "params": {"path": os.fspath(path)}},
            "svd": {"type": "image_svd", "params": {"rank": min(w, h)}, "inputs": {"image": "load.image"}},
        },
        outputs=["load", "svd"],
    )
    r = cgnodes.run(g)
    img = r["load"]["image"]
    assert img.dtype == np.float32 and img.shape == (h, w, 4)
    assert 0.0 <= img.min() and img.max() <= 1.0 and img.std() > 0.01
    np.testing.assert_allclose(r["svd"]["image"], img, atol=1e-4)


def test_a_failing_node_raises_node_error_with_node_and_socket():
    g = graph(
        {"m": {"type": "math", "params": {"op": "div", "a": 1.0, "b": 0.0}}},
        outputs=["m"],
    )
    with pytest.raises(cgnodes.NodeError) as e:
        cgnodes.run(g)
    assert isinstance(e.value, RuntimeError)
    assert (e.value.node, e.value.node_type, e.value.socket) == ("m", "math", "b")
    assert e.value.kind == "invalid_input" and "zero" in e.value.message


def test_a_bad_graph_raises_graph_error_naming_the_node():
    with pytest.raises(cgnodes.GraphError) as e:
        cgnodes.run(GRAPHS / "arithmetic.json", set={"area.op": "cube"}, targets=["pi_r2"])
    assert e.value.node == "area" and "cube" in str(e.value)
    with pytest.raises(cgnodes.GraphError, match="not a node"):
        cgnodes.run(GRAPHS / "arithmetic.json", targets=["nope"])
    with pytest.raises(cgnodes.GraphError):
        cgnodes.run(graph({"x": {"type": "no_such_node"}}, outputs=["x"]))


def test_nodes_and_describe_follow_the_declarations():
    names = cgnodes.nodes()
    assert names == sorted(names) and {"arap", "mesh_grid", "math"} <= set(names)
    d = cgnodes.describe("mesh_grid")
    assert d["type"] == "mesh_grid" and d["doc"]
    cu = next(s for s in d["inputs"] if s["name"] == "cells_u")
    assert (cu["type"], cu["default"], cu["min"], cu["max"]) == ("int", 10, 1.0, 4096.0)
    plane = next(s for s in d["inputs"] if s["name"] == "plane")
    assert plane["choices"] == ["xy", "xz", "yz"]
    assert [s["name"] for s in d["outputs"]] == ["mesh"]
    with pytest.raises(KeyError, match="mesh_grid"):
        cgnodes.describe("mesh_gird")


def test_written_files_record_the_dict_graph_node_and_params(tmp_path):
    g = graph(
        {
            "v": {"type": "value_float", "params": {"value": 1.5}},
            "save": {"type": "table_write", "params": {"path": "v.csv"}, "inputs": {"value": "v.value"}},
        }
    )
    cgnodes.run(g, out=tmp_path, frame=4)
    import json

    rec = json.loads((tmp_path / "v.csv.provenance.json").read_text())
    assert (rec["graph"], rec["node"], rec["node_type"], rec["frame"]) == ("<dict>", "save", "table_write", 4)
    assert rec["params"] == {"path": "v.csv"} and rec["graph_hash"].startswith("blake3:")
    # The hash is of the canonical JSON: the same graph with its keys in another order
    # records the same hash.
    g2 = dict(reversed(list(g.items())))
    cgnodes.run(g2, out=tmp_path / "b", frame=4)
    rec2 = json.loads((tmp_path / "b" / "v.csv.provenance.json").read_text())
    assert rec2["graph_hash"] == rec["graph_hash"]
