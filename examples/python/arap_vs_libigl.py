"""cgnodes' ARAP parameterization vs libigl's on the course cow, notebook style.

Needs the cgnodes package (`pip install ./python`) and libigl (`pip install libigl`); not run
in CI (libigl is a benchmark peer). Run from the repository root:
    python examples/python/arap_vs_libigl.py
Both start from a disk map of the same mesh (cgnodes: Tutte with mean-value weights; libigl:
harmonic), run 20 local-global iterations, and are scored with the same metric code
(bench/peers/arap_libigl.py: ARAP energy after scaling the UV area to the 3-D area, flips).
"""
import sys, time
import igl, numpy as np, cgnodes
sys.path.insert(0, "bench/peers"); from arap_libigl import arap_metric  # noqa: E402

t = time.perf_counter()
m = cgnodes.run("graphs/arap_cow.json", targets=["arap"], set={"arap.iterations": 20, "arap.tolerance": 0})["arap"]["mesh"]
t_cg = time.perf_counter() - t
V, F = m["positions"], m["faces"].astype(np.int64)
t = time.perf_counter()
bnd = igl.boundary_loop(F); U = igl.harmonic(V, F, bnd, igl.map_vertices_to_circle(V, bnd), 1)
data = igl.ARAPData(); data.max_iter = 20; igl.arap_precomputation(V, F, 2, bnd[:1], data)
U = igl.arap_solve(U[bnd[:1]], data, U)
t_igl = time.perf_counter() - t
for name, uv, s in [("cgnodes", m["uvs"], t_cg), ("libigl", U, t_igl)]:
    e, flips = arap_metric(V, F, uv)
    print(f"{name:8} ARAP energy {e:.5f}  flips {flips}  time {s * 1e3:.0f} ms")
