#!/usr/bin/env python3
"""The hard inputs of the fold-free ARAP benchmark (issue 29), made from the meshes in
assets/meshes/ with numpy alone.

Usage: arap_meshes.py OUT_DIR [SHARED_MESH_DIR]

Writes, in OUT_DIR (skipping a file that already exists):
- bunny_open.obj: bunny_closed cut open at its base (faces with a vertex below 12 % of the
  height removed) and at both ear tips (faces with a vertex above 88 % of the height removed),
  largest face-connected component kept, non-manifold vertices cleaned: a genus-0 surface with
  three boundary loops (base, two ears) and deep concavities between the ears. The committed
  copy is assets/meshes/bunny_open.obj.
- bunny_base.obj: the same cut at the base only (one boundary loop, the whole closed surface
  flattened through the base's opening). The committed copy is assets/meshes/bunny_base.obj.
- nefertiti_open4.obj: nefertiti_front with two holes punched about where the eyes are (faces
  with a vertex within 12 units of (x, z) = (+-32, 28), three boundary loops), then 1-to-4
  midpoint subdivision:
  about 175k faces, generated at benchmark time (too big for git).
- bunny_base4.obj, bunny_base16.obj: bunny_base after one and two 1-to-4 midpoint
  subdivisions (20,336 and 81,344 faces, generated at benchmark time): the same shape as
  bunny_base at 4x and 16x the faces, where libigl's harmonic start plus 20 ARAP iterations
  leaves thousands of flipped triangles.

Each file starts with comment lines saying how it was made.
"""
import os
import sys

import numpy as np


def read_obj(path):
    V, F = [], []
    with open(path) as f:
        for line in f:
            p = line.split()
            if not p:
                continue
            if p[0] == "v":
                V.append([float(x) for x in p[1:4]])
            elif p[0] == "f":
                F.append([int(x.split("/")[0]) - 1 for x in p[1:4]])
    return np.array(V), np.array(F, dtype=np.int64)


def write_obj(path, V, F, header):
    with open(path, "w") as f:
        for h in header:
            f.write("# " + h + "\n")
        for v in V:
            f.write("v %.9g %.9g %.9g\n" % tuple(v))
        for t in F:
            f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))


def compact(V, F):
    used = np.unique(F)
    remap = -np.ones(len(V), dtype=np.int64)
    remap[used] = np.arange(len(used))
    return V[used], remap[F]


def face_components(F):
    """Labels of the edge-connected components of the faces (union-find over shared edges)."""
    parent = np.arange(len(F))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    edges = {}
    for t, tri in enumerate(F):
        for k in range(3):
            e = tuple(sorted((tri[k], tri[(k + 1) % 3])))
            if e in edges:
                a, b = find(t), find(edges[e])
                parent[a] = b
            else:
                edges[e] = t
    return np.array([find(t) for t in range(len(F))])


def largest_component(F):
    lab = face_components(F)
    vals, counts = np.unique(lab, return_counts=True)
    return F[lab == vals[np.argmax(counts)]]


def nonmanifold_vertices(F, n):
    """Vertices whose faces do not form a single fan (more than one boundary-edge pair, or
    more than two boundary edges)."""
    from collections import Counter

    ec = Counter()
    for tri in F:
        for k in range(3):
            ec[tuple(sorted((tri[k], tri[(k + 1) % 3])))] += 1
    bcount = np.zeros(n, dtype=np.int64)
    bad = set()
    for (a, b), c in ec.items():
        if c == 1:
            bcount[a] += 1
            bcount[b] += 1
        elif c > 2:
            bad.update((a, b))
    bad.update(np.nonzero(bcount > 2)[0].tolist())
    return bad


def clean(V, F):
    """Largest component, then drop faces at non-manifold vertices until none is left."""
    for _ in range(20):
        F = largest_component(F)
        bad = nonmanifold_vertices(F, len(V))
        if not bad:
            break
        keep = np.array([not (set(t) & bad) for t in F])
        F = F[keep]
    return compact(V, F)


def boundary_loops(F):
    from collections import Counter

    ec = Counter()
    for tri in F:
        for k in range(3):
            ec[tuple(sorted((tri[k], tri[(k + 1) % 3])))] += 1
    nxt = {}
    for tri in F:
        for k in range(3):
            a, b = tri[k], tri[(k + 1) % 3]
            if ec[tuple(sorted((a, b)))] == 1:
                nxt[a] = b
    loops, seen = [], set()
    for s in nxt:
        if s in seen:
            continue
        loop, v = [], s
        while v not in seen:
            seen.add(v)
            loop.append(v)
            v = nxt[v]
        loops.append(loop)
    return loops


def subdivide(V, F):
    """1-to-4 midpoint subdivision (each edge split at its midpoint)."""
    edges = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    uniq, inv = np.unique(edges, axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    m = len(F)
    mid = len(V) + inv
    a, b, c = mid[:m], mid[m : 2 * m], mid[2 * m :]  # midpoints of (0,1), (1,2), (2,0)
    V2 = np.vstack([V, 0.5 * (V[uniq[:, 0]] + V[uniq[:, 1]])])
    F2 = np.vstack(
        [
            np.stack([F[:, 0], a, c], 1),
            np.stack([a, F[:, 1], b], 1),
            np.stack([c, b, F[:, 2]], 1),
            np.stack([a, b, c], 1),
        ]
    )
    return V2, F2


def bunny_open(src, top=0.88):
    V, F = read_obj(src)
    y = V[:, 1]
    lo, hi = y.min(), y.max()
    low = lo + 0.12 * (hi - lo)
    high = lo + top * (hi - lo)
    keep = ~((y[F] < low).any(1) | (y[F] > high).any(1))
    V, F = clean(V, F[keep])
    header = [
        "bunny_closed.obj (Stanford bunny via libigl-tutorial-data) cut open by bench/peers/arap_meshes.py:",
        "faces with a vertex below 12 %% or above %.0f %% of the height (y) removed, largest component,"
        % (100 * top),
        "non-manifold vertices cleaned; %d boundary loops" % len(boundary_loops(F)),
    ]
    return V, F, header


def nefertiti_open4(src):
    V, F = read_obj(src)
    # two holes about where the eyes are (the face looks down -y, z is up): faces with a
    # vertex within 12 units of (+-32, 28) in the x-z plane
    drop = np.zeros(len(F), dtype=bool)
    for cx in (-32.0, 32.0):
        near = np.hypot(V[:, 0] - cx, V[:, 2] - 28.0) < 12.0
        drop |= near[F].any(1)
    V, F = clean(V, F[~drop])
    loops = len(boundary_loops(F))
    V, F = subdivide(V, F)
    header = [
        "nefertiti_front.obj with two holes punched about where the eyes are (faces with a vertex",
        "within 12 units of (x, z) = (+-32, 28)) by bench/peers/arap_meshes.py, cleaned,",
        "then 1-to-4 midpoint subdivision; %d boundary loops" % loops,
    ]
    return V, F, header


def refined(make, times):
    """`make`'s mesh after `times` 1-to-4 midpoint subdivisions."""

    def build(src):
        V, F, header = make(src)
        for _ in range(times):
            V, F = subdivide(V, F)
        return V, F, header + ["then %d 1-to-4 midpoint subdivision(s)" % times]

    return build


def main():
    out = sys.argv[1]
    here = os.path.dirname(os.path.abspath(__file__))
    shared = sys.argv[2] if len(sys.argv) > 2 else os.path.join(here, "../../assets/meshes")
    os.makedirs(out, exist_ok=True)
    bunny_base = lambda src: bunny_open(src, top=1.0)  # noqa: E731
    for name, make, src in [
        ("bunny_open", bunny_open, "bunny_closed.obj"),
        ("bunny_base", bunny_base, "bunny_closed.obj"),
        ("nefertiti_open4", nefertiti_open4, "nefertiti_front.obj"),
        ("bunny_base4", refined(bunny_base, 1), "bunny_closed.obj"),
        ("bunny_base16", refined(bunny_base, 2), "bunny_closed.obj"),
    ]:
        path = os.path.join(out, name + ".obj")
        if os.path.exists(path):
            continue
        V, F, header = make(os.path.join(shared, src))
        write_obj(path, V, F, header)
        print("%s: %d vertices, %d faces, %s" % (path, len(V), len(F), header[-1]))


if __name__ == "__main__":
    main()
