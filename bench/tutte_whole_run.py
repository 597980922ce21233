#!/usr/bin/env python3
"""Tutte parameterization as a user runs it, whole processes, beside libigl: `cgnodes run` of
mesh_load -> tutte (cotangent weights, circle) -> mesh_save with its default run report,
against a Python process that imports libigl, reads the same OBJ, maps the boundary to the
circle, solves the harmonic map and writes the OBJ (`igl.read_triangle_mesh`,
`boundary_loop`, `map_vertices_to_circle`, `harmonic`, `writeOBJ`). Alternated over ROUNDS
rounds; writes bench/results/tutte_whole_run.json (each round's seconds, medians, ratio).

Usage: cargo build --release && pip install libigl && python3 bench/tutte_whole_run.py
"""
import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _record  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MESHES = ["camel_b", "camelhead", "nefertiti_front", "bunny_base", "igea_front"]

LIBIGL = r"""
import sys, numpy as np, igl
V, F = igl.read_triangle_mesh(sys.argv[1])
bnd = igl.boundary_loop(F)
uv = igl.harmonic(V, F, bnd, igl.map_vertices_to_circle(V, bnd), 1)
igl.writeOBJ(sys.argv[2], np.c_[uv, np.zeros(len(uv))], F)
"""


def graph(mesh):
    return {
        "format": "cgnodes-graph",
        "version": 1,
        "nodes": {
            "load": {"type": "mesh_load", "params": {"path": mesh}},
            "tutte": {"type": "tutte", "params": {"weights": "cotangent", "boundary": "circle"},
                      "inputs": {"mesh": "load.mesh"}},
            "save": {"type": "mesh_save", "params": {"path": "flat.obj"},
                     "inputs": {"mesh": "tutte.mesh"}},
        },
    }


def timed(args):
    t = time.perf_counter()
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--bin", default=os.path.join(ROOT, "target/release/cgnodes"))
    a = ap.parse_args()
    try:
        import igl  # noqa: F401
    except ImportError:
        print("libigl is not installed: pip install libigl", file=sys.stderr)
        return 2
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        script = os.path.join(tmp, "tutte_libigl.py")
        with open(script, "w") as f:
            f.write(LIBIGL)
        for name in MESHES:
            mesh = os.path.join(ROOT, "assets/meshes", name + ".obj")
            g = os.path.join(tmp, name + ".json")
            with open(g, "w") as f:
                json.dump(graph(mesh), f)
            ours_cmd = [a.bin, "run", g, "--out", os.path.join(tmp, "out"), "-q"]
            igl_cmd = [sys.executable, script, mesh, os.path.join(tmp, "igl.obj")]
            timed(ours_cmd), timed(igl_cmd)  # warm the page cache
            ours, peer = [], []
            for _ in range(a.rounds):
                ours.append(timed(ours_cmd))
                peer.append(timed(igl_cmd))
            mo, mp = statistics.median(ours), statistics.median(peer)
            rows.append({"mesh": name, "cgnodes_s": ours, "libigl_s": peer,
                         "median_cgnodes_s": mo, "median_libigl_s": mp, "ratio": mo / mp})
            print(f"{name:16s} cgnodes {mo*1e3:8.1f} ms  libigl {mp*1e3:8.1f} ms  ratio {mo/mp:5.2f}")
    _record.write("tutte_whole_run", "python3 bench/tutte_whole_run.py --rounds %d" % a.rounds, peer="libigl (pip), Python " + platform.python_version(), rounds=a.rounds, meshes=rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
