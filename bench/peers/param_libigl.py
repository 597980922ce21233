#!/usr/bin/env python3
"""libigl side of the parameterization benchmark (run by `cargo bench --bench param`).

Reads the manifest written by bench/param.rs: for each mesh, the exact positions and triangles
cgnodes used (raw float64 / int64), cgnodes' median times and UVs. Times libigl 2.6.3
(`pip install libigl`) on the same data in the same run -- boundary_loop + map_vertices_to_circle
+ harmonic (cotangent) or a uniform Laplacian through min_quad_with_fixed -- and compares the UVs
after the best similarity (rotation/reflection, scale, translation; Umeyama 1991) between the
two circle placements (cgnodes: centre (1/2, 1/2), radius 1/2; libigl: unit circle).
Prints a markdown table.
"""
import json
import sys
import time

import numpy as np

try:
    import igl
    import scipy.sparse as sp
except ImportError:
    print("libigl is not installed: pip install libigl", file=sys.stderr)
    sys.exit(2)


def libigl_tutte(V, F, weights):
    bnd = igl.boundary_loop(F)
    bnd_uv = igl.map_vertices_to_circle(np.asfortranarray(V), bnd.astype(np.int32))
    if weights == "cotangent":
        return igl.harmonic(V, F, bnd, np.ascontiguousarray(bnd_uv), 1)
    A = igl.adjacency_matrix(F).astype(np.float64)
    L = sp.diags(np.asarray(A.sum(axis=1)).ravel()) - A  # positive semidefinite uniform Laplacian
    L = sp.csc_matrix(L)
    B = np.zeros((V.shape[0], 2))
    empty = sp.csc_matrix((0, V.shape[0]))
    return igl.min_quad_with_fixed(L, B, bnd, np.ascontiguousarray(bnd_uv), empty, np.zeros((0, 2)), True)


def similarity_residual(X, Y):
    """Max |s R X + t - Y| over the best similarity (Umeyama 1991, reflections allowed)."""
    mx, my = X.mean(0), Y.mean(0)
    Xc, Yc = X - mx, Y - my
    U, S, Vt = np.linalg.svd(Yc.T @ Xc)
    R = U @ Vt
    s = S.sum() / (Xc ** 2).sum()
    Z = s * Xc @ R.T + my
    return np.abs(Z - Y).max()


def median_ms(f, reps):
    f()  # warm-up
    ts = []
    for _ in range(reps):
        t0 = time.perf_counter()
        out = f()
        ts.append((time.perf_counter() - t0) * 1e3)
    return float(np.median(ts)), out


def main():
    man = json.load(open(sys.argv[1]))
    print("| mesh (faces) | weights | cgnodes ms | libigl ms | cgnodes / libigl | max UV difference after similarity (libigl units) |")
    print("|---|---|---|---|---|---|")
    for m in man["meshes"]:
        V = np.fromfile(m["V"], dtype="<f8").reshape(-1, 3)
        F = np.fromfile(m["F"], dtype="<i8").reshape(-1, 3)
        for w, ours in m["ours"].items():
            if w not in ("uniform", "cotangent"):
                continue
            ms, uv = median_ms(lambda: libigl_tutte(V, F, w), m["reps"])
            our_uv = np.fromfile(ours["uv"], dtype="<f8").reshape(-1, 2)
            err = similarity_residual(our_uv, np.asarray(uv)[:, :2])
            print(f"| {m['name']} ({F.shape[0]:,}) | {w} | {ours['ms']:.1f} | {ms:.1f} | {ours['ms'] / ms:.2f} | {err:.1e} |")


if __name__ == "__main__":
    main()
