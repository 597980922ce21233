#!/usr/bin/env python3
"""Mitsuba 3 peer for `cargo bench --bench trace -- --rays [--scene igea]`: traces the rays
that run wrote (target/trace_bench/rays_<scene>.bin: camera rays, three bounces of
cosine-sampled rays and shadow rays to the light, as a path tracer meets them) through the
same scene with `llvm_ad_rgb` (Embree under Dr.Jit's wavefront), closest hits with
`ray_intersect_preliminary` and shadow rays with `ray_test`, and prints millions of rays
per CPU-second and the hit count (the bench prints ours).

    python3 bench/peers/rays_mitsuba.py [--scene box|igea] [--igea PATH] [--variant V]

Timing: process CPU seconds (Dr.Jit's worker threads included) of each of five runs after a
warm-up run that compiles the kernels, best of five. Installs `mitsuba` and `numpy` with
pip if they are missing (`_mitsuba.py`).
"""
import argparse, os, time

from _mitsuba import import_mitsuba, scene_dict

mi = import_mitsuba()
import numpy as np  # noqa: E402
import drjit as dr  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("--scene", default="box", choices=["box", "igea"])
ap.add_argument("--igea", default="assets/meshes/igea_front.obj")
ap.add_argument("--variant", default="llvm_ad_rgb")
ap.add_argument("--dir", default=os.path.join(os.path.dirname(__file__), "..", "..", "target", "trace_bench"))
a = ap.parse_args()

raw = open(os.path.join(a.dir, f"rays_{a.scene}.bin"), "rb").read()
nc, ns = np.frombuffer(raw[:8], dtype="<u4")
r = np.frombuffer(raw[8:], dtype="<f4").reshape(-1, 7)
assert len(r) == nc + ns, "rays file truncated"
mi.set_variant(a.variant)
scene = mi.load_dict(scene_dict(mi, a.scene, a.igea))


def rays(x):
    # Our shadow rays run from the offset point to the light point with tmax 1 - 1e-4, the
    # direction unnormalised; Mitsuba's rays take the same (o, d, maxt) as they are.
    maxt = np.where(np.isfinite(x[:, 6]), x[:, 6], 3.0e38).astype(np.float32)
    return mi.Ray3f(mi.Point3f(*[mi.Float(np.ascontiguousarray(x[:, k])) for k in range(3)]),
                    mi.Vector3f(*[mi.Float(np.ascontiguousarray(x[:, k])) for k in range(3, 6)]),
                    mi.Float(maxt), mi.Float(0.0), mi.Color0f())


def run():
    closest, shadow = rays(r[:nc]), rays(r[nc:])
    dr.eval(closest, shadow)
    c0 = time.process_time()
    si = scene.ray_intersect_preliminary(closest, coherent=False)
    blocked = scene.ray_test(shadow, coherent=False)
    hits = dr.count(si.is_valid()) + dr.count(blocked)
    dr.eval(hits)
    h = int(hits[0] if hasattr(hits, "__getitem__") else hits)
    return time.process_time() - c0, h


run()  # warm up: compiles the kernels
best, hits = min(run() for _ in range(5))
print(f"{a.variant} {a.scene}: {nc} closest-hit and {ns} shadow rays, {hits} hits, "
      f"{(nc + ns) / best / 1e6:.2f} Mrays per CPU-second ({best:.3f} s CPU)")
