#!/usr/bin/env python3
"""libigl's SLIM (symmetric Dirichlet) from a given start, timed per iteration, and the
metrics of both SLIM's and cgnodes' fold-free ARAP iterates, for bench/arap_slim.rs.

Usage: arap_slim.py PREFIX ITERATIONS

Reads PREFIX.v (n x 3 float64), PREFIX.f (m x 3 int32) and PREFIX.init (n x 2 float64: the
start, cgnodes' Tutte map, as written by bench/arap_slim.rs in cgnodes' vertex order), and
PREFIX.ours.K (n x 2 float64, cgnodes' fold-free ARAP after K iterations) for the K listed in
PREFIX.ours.json. The start is scaled to the 3-D area (symmetric Dirichlet is not scale
invariant and blows up on a map much smaller than the mesh; a uniform scale keeps it
fold-free), then igl.slim_precompute (SYMMETRIC_DIRICHLET, no constraint) and
igl.slim_solve(data, 1) ITERATIONS times. After each iteration (outside the timing): the ARAP
energy as ARAP minimizes it (sum A ((s1-1)^2 + (s2-1)^2) / sum A, UVs unscaled), the worst
triangle (largest s1/s2 over triangles; inf when one is flipped or degenerate) and the flips
(against the majority orientation). Writes PREFIX.slim.csv with one row per point of both
methods: method, iteration, ms, arap_energy, worst_ratio, flips. Needs `pip install libigl`.
"""
import json
import os
import sys
import time

import igl
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from arap_libigl import stretches  # noqa: E402


def metrics(V, F, U):
    """ARAP energy (UVs unscaled), worst triangle s1/s2 (inf if flipped or degenerate), flips."""
    a3, s1, s2, pos, neg = stretches(V, F, U, scaled=False)
    energy = float((a3 * ((s1 - 1) ** 2 + (s2 - 1) ** 2)).sum() / a3.sum())
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(s2 > 0, s1 / s2, np.inf)
    return energy, float(ratio.max()), len(F) - max(pos, neg)


def main():
    prefix, iters = sys.argv[1], int(sys.argv[2])
    V = np.fromfile(prefix + ".v", dtype="<f8").reshape(-1, 3)
    F = np.fromfile(prefix + ".f", dtype="<i4").reshape(-1, 3)
    U0 = np.fromfile(prefix + ".init", dtype="<f8").reshape(-1, 2)
    rows = []
    with open(prefix + ".ours.json") as f:
        ours = json.load(f)
    for k, ms in ours["checkpoints"]:
        U = np.fromfile("%s.ours.%d" % (prefix, k), dtype="<f8").reshape(-1, 2)
        rows.append(("ours fold-free ARAP", k, ms) + metrics(V, F, U))

    # SLIM from the same map, scaled to the 3-D area
    _, _, fl = metrics(V, F, U0)
    a3 = igl.doublearea(V, F).sum()
    auv = np.abs(igl.doublearea(U0, F)).sum()
    U = np.asfortranarray(U0 * np.sqrt(a3 / auv))
    b = np.zeros(0, dtype=np.int32)
    bc = np.zeros((0, 2), dtype=np.float64)
    t0 = time.perf_counter()
    data = igl.slim_precompute(
        np.asfortranarray(V), np.asfortranarray(F), U, igl.SYMMETRIC_DIRICHLET, b, bc, 0.0
    )
    elapsed = time.perf_counter() - t0
    rows.append(("SLIM (libigl)", 0, elapsed * 1e3) + metrics(V, F, U))
    for it in range(1, iters + 1):
        t0 = time.perf_counter()
        U = igl.slim_solve(data, 1)
        elapsed += time.perf_counter() - t0
        rows.append(("SLIM (libigl)", it, elapsed * 1e3) + metrics(V, F, U[:, :2]))
    with open(prefix + ".slim.csv", "w") as f:
        f.write("method,iteration,ms,arap_energy,worst_ratio,flips\n")
        for r in rows:
            f.write("%s,%d,%.3f,%.9g,%.9g,%d\n" % r)


if __name__ == "__main__":
    main()
