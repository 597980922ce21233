#!/usr/bin/env python3
"""usd-core's `UsdSkel.SkinPointsLBS` on the mesh `cargo bench --bench skin` writes: the
benchmark hands over a folder with `points.f64`, `indices.i32`, `weights.f64` (little endian,
row-major), `xforms.f64` (one row-major 4x4 per joint per frame, USD row-vector convention)
and `meta.json` (vertices, influences, joints, frames); this script skins every frame
`repeat` times and prints one JSON line: the median milliseconds per frame and, per frame,
the largest coordinate difference to cgnodes' points in `ours.f64` (relative to the bounding
box diagonal), so that both sides are known to compute the same thing.

    python3 bench/peers/skin_usd.py DIR

Installs `usd-core` and `numpy` into target/peers-venv when they are missing.
"""
import json
import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import _images  # noqa: E402  (the peers' virtual environment)

_images.ensure(["pxr", "numpy"], ["usd-core", "numpy"], __file__, "SKIN_PEER_INSTALLED")
import numpy as np  # noqa: E402
from pxr import Gf, UsdSkel, Vt  # noqa: E402

d = sys.argv[1]
meta = json.load(open(os.path.join(d, "meta.json")))
n, k, nj, frames, repeat = meta["vertices"], meta["influences"], meta["joints"], meta["frames"], meta["repeat"]
points = np.fromfile(os.path.join(d, "points.f64"), "<f8").reshape(n, 3)
idx = Vt.IntArray.FromNumpy(np.fromfile(os.path.join(d, "indices.i32"), "<i4"))
w = Vt.FloatArray.FromNumpy(np.fromfile(os.path.join(d, "weights.f64"), "<f8").astype(np.float32))
xf = np.fromfile(os.path.join(d, "xforms.f64"), "<f8").reshape(frames, nj, 4, 4)
ours = np.fromfile(os.path.join(d, "ours.f64"), "<f8").reshape(frames, n, 3)
rest = Vt.Vec3fArray.FromNumpy(points.astype(np.float32))
diag = float(np.linalg.norm(points.max(0) - points.min(0)))
times, diffs = [], []
for f in range(frames):
    mats = Vt.Matrix4dArray([Gf.Matrix4d(*[float(x) for x in m.reshape(-1)]) for m in xf[f]])
    for r in range(repeat):
        p = Vt.Vec3fArray(rest)
        t0 = time.perf_counter()
        ok = UsdSkel.SkinPointsLBS(Gf.Matrix4d(1), mats, idx, w, k, p)
        times.append(time.perf_counter() - t0)
        assert ok
    diffs.append(float(np.abs(np.array(p, dtype=np.float64) - ours[f]).max()) / diag)
print(json.dumps({"ms_per_frame": 1e3 * statistics.median(times), "max_rel_diff": max(diffs), "threads": "usd-core default (WorkParallelForN)"}))
