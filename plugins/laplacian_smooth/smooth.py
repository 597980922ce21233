#!/usr/bin/env python3
"""cgnodes plugin `laplacian_smooth`: uniform Laplacian smoothing with numpy.

Each step moves every free vertex a fraction `lambda` of the way to the average of its
edge neighbours,

    p_i <- p_i + lambda * (1/|N(i)| * sum_{j in N(i)} p_j - p_i),

the explicit umbrella-operator step of Taubin, "A signal processing approach to fair surface
design", SIGGRAPH 1995, eq. 3-4 with uniform weights.

Protocol (docs/plugins.md): one JSON request on stdin, one JSON response on stdout, log lines
on stderr; arrays travel as .npy files in the request's `call_dir`.
"""

import json
import os
import sys

import numpy as np

PROTOCOL = 1


def log(*args):
    print(*args, file=sys.stderr)


def mesh_edges(counts, indices, n):
    """Unique undirected edges (e0, e1) of a polygon mesh and the vertices on its boundary
    (edges that only one face uses)."""
    counts = counts.astype(np.int64)
    indices = indices.astype(np.int64)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    nxt = np.arange(len(indices), dtype=np.int64) + 1
    nxt[starts + counts - 1] = starts  # the last corner of each face wraps to its first
    a, b = indices, indices[nxt]
    key = np.minimum(a, b) * n + np.maximum(a, b)
    uniq, uses = np.unique(key, return_counts=True)
    e0, e1 = uniq // n, uniq % n
    boundary = np.zeros(n, dtype=bool)
    boundary[e0[uses == 1]] = True
    boundary[e1[uses == 1]] = True
    return e0, e1, boundary


def smooth(positions, counts, indices, iterations, lam, fix_boundary):
    if iterations == 0:
        return positions.copy()
    n = len(positions)
    e0, e1, boundary = mesh_edges(counts, indices, n)
    degree = np.bincount(e0, minlength=n) + np.bincount(e1, minlength=n)
    free = degree > 0
    if fix_boundary:
        free &= ~boundary
    p = positions.copy()
    for _ in range(iterations):
        total = np.empty_like(p)
        for c in range(3):
            total[:, c] = np.bincount(e0, weights=p[e1, c], minlength=n) + np.bincount(
                e1, weights=p[e0, c], minlength=n
            )
        avg = total[free] / degree[free, None]
        p[free] += lam * (avg - p[free])
    return p


def main():
    req = json.load(sys.stdin)
    if req.get("protocol") != PROTOCOL:
        json.dump({"protocol": PROTOCOL, "error": f"protocol {req.get('protocol')} is not supported"}, sys.stdout)
        return
    if req["node"] != "laplacian_smooth":
        json.dump({"protocol": PROTOCOL, "error": f"unknown node {req['node']}"}, sys.stdout)
        return
    inp = req["inputs"]
    mesh = inp["mesh"]
    positions = np.load(mesh["positions"])
    counts = np.load(mesh["face_counts"])
    indices = np.load(mesh["face_indices"])
    out = smooth(positions, counts, indices, inp["iterations"], inp["lambda"], inp["fix_boundary"])
    path = os.path.join(req["call_dir"], "smoothed_positions.npy")
    np.save(path, out)
    moved = float(np.max(np.linalg.norm(out - positions, axis=1))) if len(out) else 0.0
    log(f"smoothed {len(out)} vertices with {inp['iterations']} steps of {inp['lambda']}")
    json.dump(
        {
            "protocol": PROTOCOL,
            # `base`: keep the input mesh's faces, UVs and attributes; replace the positions.
            "outputs": {"mesh": {"base": "mesh", "positions": "smoothed_positions.npy"}, "max_displacement": moved},
        },
        sys.stdout,
    )


if __name__ == "__main__":
    main()
