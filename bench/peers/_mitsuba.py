"""Shared set-up of the Mitsuba 3 peers (trace_mitsuba.py, rays_mitsuba.py, env_mitsuba.py):
where Dr.Jit finds LLVM, the packages they install, and the trace bench's scenes."""
import glob
import os
import subprocess
import sys


def point_at_llvm():
    """Dr.Jit finds LLVM through DRJIT_LIBLLVM_PATH; Debian bookworm's default LLVM 15 aborts
    in llvm_ad_rgb, so point it at libllvm19 (apt-get install libllvm19) when that is
    installed. Call before importing mitsuba."""
    if "DRJIT_LIBLLVM_PATH" not in os.environ:
        found = sorted(glob.glob("/usr/lib/*/libLLVM.so.19*") + glob.glob("/usr/lib/*/libLLVM-19.so"))
        if found:
            os.environ["DRJIT_LIBLLVM_PATH"] = found[0]


def import_mitsuba():
    """Points Dr.Jit at LLVM, pip-installs numpy and mitsuba when they are missing, and
    returns the mitsuba module."""
    point_at_llvm()
    for mod in ["numpy", "mitsuba"]:
        try:
            __import__(mod)
        except ImportError:
            subprocess.check_call([sys.executable, "-m", "pip", "install", "-q", mod])
    import mitsuba
    return mitsuba


def scene_dict(mi, scene, igea):
    """The trace bench's scene as a Mitsuba dict: mi.cornell_box() with a box filter, and
    with `scene == "igea"` the igea scan placed as `cargo bench --bench trace` places it."""
    d = mi.cornell_box()
    d["sensor"]["film"]["rfilter"] = {"type": "box"}
    if scene == "igea":
        import numpy as np
        v = np.array([[float(x) for x in ln.split()[1:4]] for ln in open(igea) if ln.startswith("v ")])
        lo, hi = v.min(axis=0), v.max(axis=0)
        s = 0.8 / (hi - lo).max()
        T = mi.ScalarTransform4f
        d["igea"] = {"type": "obj", "filename": igea, "bsdf": {"type": "ref", "id": "white"},
                     "to_world": T().translate([0.0, -0.2, 0.2]).scale([float(s)] * 3).translate((-(lo + hi) / 2).tolist())}
    return d
