#!/usr/bin/env python3
"""libigl's ARAP parameterization, timed per iteration, for bench/arap.rs.

Usage: arap_libigl.py MESH.obj ITERATIONS OUT_PREFIX

Starts from igl.harmonic (cotangent, boundary on the unit circle by arc length), pins one vertex
(the first boundary vertex, at its harmonic position), with_dynamics = False, and calls
igl.arap_solve one iteration at a time (max_iter = 1, warm-started from the previous UVs; the
state of libigl's ARAP between iterations is the UVs alone) so that energy and flips can be
logged after each (`energy`: UV area scaled to the 3-D area first; `energy_raw`:
unscaled, the quantity ARAP minimizes). Writes OUT_PREFIX.json (timings, per-iteration log), OUT_PREFIX.uv
(final UVs, little-endian float64, n x 2) and OUT_PREFIX.v (libigl's vertex positions, n x 3, to
match its vertex order with ours) so that cgnodes measures both results with the same
metric code. Needs `pip install libigl` (2.6).
"""
import json
import sys
import time

import igl
import numpy as np


def stretches(V, F, U, scaled=True):
    """Per triangle: 3-D area, singular values s1 >= s2 of the map's Jacobian (s2 negative on
    a triangle flipped against the majority orientation), and the counts of positive and
    negative UV orientations. `scaled` first scales the UVs to the 3-D area."""
    p0, p1, p2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    e1, e2 = p1 - p0, p2 - p0
    l1 = np.linalg.norm(e1, axis=1)
    cr = np.linalg.norm(np.cross(e1, e2), axis=1)
    x2 = np.einsum("ij,ij->i", e1, e2) / l1
    y2 = cr / l1
    a3 = 0.5 * cr
    u0, u1, u2 = U[F[:, 0]], U[F[:, 1]], U[F[:, 2]]
    du1, du2 = u1 - u0, u2 - u0
    det_uv = du1[:, 0] * du2[:, 1] - du1[:, 1] * du2[:, 0]
    auv = 0.5 * np.abs(det_uv).sum()
    s = np.sqrt(a3.sum() / auv) if scaled else 1.0
    # J = [du1 du2] [[l1, x2], [0, y2]]^-1
    a = du1[:, 0] / l1
    c = du1[:, 1] / l1
    b = (du2[:, 0] - a * x2) / y2
    d = (du2[:, 1] - c * x2) / y2
    a, b, c, d = a * s, b * s, c * s, d * s
    E, H = 0.5 * (a + d), 0.5 * (c - b)
    Fm, G = 0.5 * (a - d), 0.5 * (c + b)
    q, r = np.hypot(E, H), np.hypot(Fm, G)
    pos, neg = int((det_uv > 0).sum()), int((det_uv < 0).sum())
    maj = 1.0 if pos >= neg else -1.0
    return a3, q + r, (q - r) * maj, pos, neg


def arap_metric(V, F, U, scaled=True):
    """ARAP energy sum A((s1-1)^2+(s2-1)^2)/sum A after scaling UV area to 3D area, and flips
    against the majority orientation (as uv_metrics does)."""
    a3, s1, s2, pos, neg = stretches(V, F, U, scaled)
    energy = float((a3 * ((s1 - 1) ** 2 + (s2 - 1) ** 2)).sum() / a3.sum())
    flips = int(len(F) - max(pos, neg))
    return energy, flips


def main():
    path, iters, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    V, F = igl.read_triangle_mesh(path)
    t0 = time.perf_counter()
    bnd = igl.boundary_loop(F)
    bnd_uv = igl.map_vertices_to_circle(V, bnd.astype(np.int32))
    U = igl.harmonic(V, F, bnd, bnd_uv, 1)
    t_harmonic = time.perf_counter() - t0

    b = np.array([bnd[0]], dtype=np.int32)
    bc = U[b].copy()
    t0 = time.perf_counter()
    data = igl.ARAPData()
    data.with_dynamics = False
    data.max_iter = 1
    igl.arap_precomputation(V, F, 2, b, data)
    t_pre = time.perf_counter() - t0

    e, fl = arap_metric(V, F, U)
    raw, _ = arap_metric(V, F, U, scaled=False)
    log = [{"iteration": 0, "elapsed_ms": 0.0, "energy": e, "energy_raw": raw, "flips": fl}]
    solve_s = 0.0
    for it in range(1, iters + 1):
        t0 = time.perf_counter()
        U = igl.arap_solve(bc, data, U)
        solve_s += time.perf_counter() - t0
        e, fl = arap_metric(V, F, U)
        raw, _ = arap_metric(V, F, U, scaled=False)
        log.append(
            {"iteration": it, "elapsed_ms": solve_s * 1e3, "energy": e, "energy_raw": raw, "flips": fl}
        )

    np.ascontiguousarray(U[:, :2], dtype="<f8").tofile(out + ".uv")
    np.ascontiguousarray(V, dtype="<f8").tofile(out + ".v")
    with open(out + ".json", "w") as f:
        json.dump(
            {
                "faces": int(len(F)),
                "vertices": int(len(V)),
                "harmonic_ms": t_harmonic * 1e3,
                "precompute_ms": t_pre * 1e3,
                "iteration_ms": solve_s * 1e3 / max(iters, 1),
                "log": log,
            },
            f,
        )


if __name__ == "__main__":
    main()
