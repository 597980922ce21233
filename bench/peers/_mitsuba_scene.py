"""The trace bench's scenes for Mitsuba 3, shared by trace_mitsuba.py and rays_mitsuba.py."""


def scene_dict(mi, scene, igea):
    """The bench's scene as a Mitsuba dict: mi.cornell_box() with a box filter, and with
    `scene == "igea"` the igea scan placed as `cargo bench --bench trace` places it."""
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

