#!/usr/bin/env python3
"""Mitsuba 3 against cgnodes' `render_path` under an environment map (issue 28).

    python3 bench/peers/env_mitsuba.py [--size 128] [--spp 1024] [--variant llvm_ad_rgb]
                                       [--rotation 60] [--check-only] [--docs] [--reuse]

`--reuse` keeps cgnodes' two renders from an earlier run (target/env_mitsuba/cgnodes_*.exr)
and renders only Mitsuba again. The docs' figures: `--size 256 --spp 1024 --docs`.

Scene (written by this script into target/env_mitsuba/, the same files for both renderers):
a UV sphere of radius 1 (48x24 segments, per-vertex normals `vn`, UVs `vt`) whose diffuse
albedo is a 64x32 sRGB PNG texture (a colour ramp in u and v under a 8x4 checker, so that a
flipped or shifted lookup shows), standing on a grey diffuse ground quad (albedo 0.5), lit
only by `assets/envmaps/sky.exr` turned by `--rotation` degrees about +y; pinhole camera,
box pixel filter, path tracing with max_depth 8 and roulette from depth 5 in both.

The environment is the same scene for both through two documented transforms:
- Orientation. cgnodes' `light_environment` looks up u = 1/2 + atan2(x, -z) / (2 pi) (the
  image centre along -z) and turns the sky counter-clockwise about +y seen from above by
  `rotation`. Mitsuba's `envmap` looks up u = atan2(x, -z) / (2 pi) (the image's left edge
  along -z) in the frame of its `to_world`. So Mitsuba gets
  `to_world = rotate(+y, rotation + 180)`. `--check-only` checks this: it renders the bare
  sky (camera inside it, nothing else) with both, for four candidate transforms, and
  prints the RMSE of each (the right one is far smaller than the others).
- Filtering. Mitsuba interpolates the envmap bilinearly, with column centres at
  (i + 1/2) / w but row centres at v = i / (h - 1) (its v spans h - 1 rows, so a feature
  of the map covers h / (h - 1) times the polar angle it covers in ours: +3 % for sky.exr's
  32 rows); `light_environment` looks up the texel (nearest, centres at (i + 1/2) / w and
  (i + 1/2) / h). Mitsuba gets sky.exr resampled (nearest, numpy) to 32 times the rows and
  8 times the columns at its own texel centres, so its bilinear lookup equals our nearest
  one except within half a fine texel of the original texel edges, and its stretch of v is
  1 + 1/1023 (with 8 times the rows it was 1 + 1/255, and the images differed by 0.4 %).
- Texture. The OBJ's `vt` have v up (OBJ convention) for cgnodes; Mitsuba gets the same
  mesh from arrays (`mi.Mesh`) with v flipped (Mitsuba's bitmap rows start at v = 0,
  its OBJ loader flips v the same way), and both filter the texture bilinearly (level 0,
  repeat) after decoding sRGB to linear.

Renders each renderer twice at `--spp` with two seeds, then prints one JSON object: mean
RGB of each image and the relative differences, the RMSE between cgnodes and Mitsuba
(seed 1 each) and the noise floor sqrt((RMSE(c1, c2)^2 + RMSE(m1, m2)^2) / 2), which is
what the RMSE of two independent unbiased renders of the same scene should be; wall and
CPU seconds of each render. Images go to target/env_mitsuba/ (EXR) and, as sRGB PNGs,
to docs/images/env_mitsuba_{cgnodes,mitsuba}.png with `--docs`.

Installs mitsuba and numpy into target/peers-venv when they are missing (PyPI);
llvm_ad_rgb needs LLVM 19 (Debian's libllvm19), as in trace_mitsuba.py.
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import _images  # noqa: E402
import _mitsuba  # noqa: E402

_mitsuba.point_at_llvm()

SEGS, RINGS = 48, 24
EYE, TARGET, FOV = [0.0, 1.4, 4.6], [0.0, -0.25, 0.0], 38.0


def sphere():
    """UV sphere of radius 1: positions, normals, uvs (v up) and triangles, seam duplicated."""
    import numpy as np

    th = np.linspace(0.0, np.pi, RINGS + 1)
    ph = np.linspace(0.0, 2.0 * np.pi, SEGS + 1)
    t, p = np.meshgrid(th, ph, indexing="ij")
    pos = np.stack([np.sin(t) * np.sin(p), np.cos(t), np.sin(t) * np.cos(p)], -1).reshape(-1, 3)
    uv = np.stack([p / (2 * np.pi), 1.0 - t / np.pi], -1).reshape(-1, 2)
    faces = []
    for i in range(RINGS):
        for j in range(SEGS):
            a, b = i * (SEGS + 1) + j, i * (SEGS + 1) + j + 1
            c, d = a + SEGS + 1, b + SEGS + 1
            if i > 0:
                faces.append([a, c, b])  # counter-clockwise seen from outside
            if i < RINGS - 1:
                faces.append([b, c, d])
    return pos, pos.copy(), uv, np.array(faces, np.int64)


def ground():
    import numpy as np

    s, y = 6.0, -1.0
    pos = np.array([[-s, y, -s], [-s, y, s], [s, y, s], [s, y, -s]], float)
    nrm = np.tile([0.0, 1.0, 0.0], (4, 1))
    uv = np.array([[0, 0], [0, 1], [1, 1], [1, 0]], float)
    return pos, nrm, uv, np.array([[0, 1, 2], [0, 2, 3]], np.int64)


def write_obj(path, mesh):
    pos, nrm, uv, f = mesh
    with open(path, "w") as o:
        o.writelines(f"v {a:.9g} {b:.9g} {c:.9g}\n" for a, b, c in pos)
        o.writelines(f"vt {a:.9g} {b:.9g}\n" for a, b in uv)
        o.writelines(f"vn {a:.9g} {b:.9g} {c:.9g}\n" for a, b, c in nrm)
        o.writelines("f " + " ".join(f"{k + 1}/{k + 1}/{k + 1}" for k in t) + "\n" for t in f)


def texture():
    import numpy as np

    h, w = 32, 64
    y, x = np.mgrid[0:h, 0:w]
    chk = ((x // 8 + y // 8) % 2).astype(float)
    img = np.stack([0.15 + 0.8 * x / w, 0.15 + 0.7 * (1 - y / h), 0.2 + 0.6 * chk], -1)
    return (255 * (0.55 * img + 0.45 * chk[..., None] * np.array([0.9, 0.8, 0.3]))).clip(0, 255).round()


def cgnodes_graph(d, a, seed, bare):
    cam = {"eye": EYE, "target": TARGET, "fov": FOV, "width": a.size, "height": a.size}
    if bare:  # the bare sky seen from the origin, wide angle
        cam = {"eye": [0, 0, 0], "target": [0.3, 0.25, -1.0], "fov": 100.0, "width": a.size, "height": a.size}
    nodes = {
        "sky_image": {"type": "image_load", "params": {"path": os.path.join(ROOT, "assets/envmaps/sky.exr"), "color_space": "raw"}},
        "sky": {"type": "light_environment", "params": {"intensity": 1.0, "rotation": a.rotation}, "inputs": {"image": "sky_image.image"}},
        "cam": {"type": "camera", "params": cam},
        "render": {"type": "render_path", "params": {"spp": a.spp if not bare else 16, "max_depth": 8, "rr_depth": 5, "seed": seed,
                                                     "filter": "box", "crease_angle": 180.0}, "inputs": {"scene": "scene.scene"}},
        "save": {"type": "image_save", "params": {"path": "color.exr"}, "inputs": {"image": "render.color"}},
    }
    if bare:
        # A tiny quad behind the camera, so that the scene has a mesh; never seen.
        nodes["m0"] = {"type": "mesh_load", "params": {"path": os.path.join(d, "ground.obj")}}
        nodes["t0"] = {"type": "mesh_transform", "params": {"translate": [0, 0, 50], "scale": [0.01, 0.01, 0.01]}, "inputs": {"mesh": "m0.mesh"}}
        nodes["mat0"] = {"type": "material", "params": {"base_color": [0.5, 0.5, 0.5]}}
        nodes["scene"] = {"type": "scene", "inputs": {"meshes": ["t0.mesh"], "materials": ["mat0.material"], "lights": "sky.light", "camera": "cam.camera"}}
    else:
        nodes["m0"] = {"type": "mesh_load", "params": {"path": os.path.join(d, "sphere.obj")}}
        nodes["m1"] = {"type": "mesh_load", "params": {"path": os.path.join(d, "ground.obj")}}
        nodes["tex"] = {"type": "image_load", "params": {"path": os.path.join(d, "texture.png")}}
        nodes["mat0"] = {"type": "material", "params": {"base_color": [1.0, 1.0, 1.0], "roughness": 1.0}, "inputs": {"texture": "tex.image"}}
        nodes["mat1"] = {"type": "material", "params": {"base_color": [0.5, 0.5, 0.5], "roughness": 1.0}}
        nodes["scene"] = {"type": "scene", "inputs": {"meshes": ["m0.mesh", "m1.mesh"], "materials": ["mat0.material", "mat1.material"],
                                                      "lights": "sky.light", "camera": "cam.camera"}}
    return nodes


def run_cgnodes(d, a, seed, bare=False):
    import numpy as np

    tag = f"cgnodes_{'bare' if bare else 'scene'}_{seed}"
    g = os.path.join(d, tag + ".json")
    with open(g, "w") as f:
        json.dump({"format": "cgnodes-graph", "version": 1, "nodes": cgnodes_graph(d, a, seed, bare)}, f)
    out = os.path.join(d, tag)
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([_images.cgnodes_bin(), "run", g, "--out", out, "--no-report"], check=True, capture_output=True)
    secs = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime + r1.ru_stime) - (r0.ru_utime + r0.ru_stime)
    import mitsuba as mi

    img = np.array(mi.Bitmap(os.path.join(out, "color.exr")), dtype=np.float64)[..., :3]
    return img, secs, cpu


def mitsuba_scene(d, a, to_world_deg, bare):
    import mitsuba as mi
    import numpy as np

    T = mi.ScalarTransform4f
    sky = np.array(mi.Bitmap(os.path.join(ROOT, "assets/envmaps/sky.exr")), dtype=np.float32)[..., :3]
    # Resampled finer (nearest) at the places Mitsuba puts its texel centres: columns at
    # (x + 1/2) / w', rows at y / (h' - 1). Mitsuba spreads h' rows over h' - 1 row widths
    # of v, so a feature of the map covers h' / (h' - 1) times its polar extent in ours;
    # 32 times as many rows bring that to 1 + 1/1023 (8 times: 1 + 1/255, +0.4 % on the sun).
    h, w = sky.shape[:2]
    fy, fx = 32, 8
    rows = np.minimum((np.arange(fy * h) / (fy * h - 1) * h).astype(int), h - 1)
    cols = np.minimum(((np.arange(fx * w) + 0.5) / (fx * w) * w).astype(int), w - 1)
    up = np.ascontiguousarray(sky[rows][:, cols])
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 8, "rr_depth": 5},
        "env": {"type": "envmap", "bitmap": mi.Bitmap(up), "to_world": T().rotate([0, 1, 0], to_world_deg)},
    }
    if bare:
        origin, target, fov = [0, 0, 0], [0.3, 0.25, -1.0], 100.0
    else:
        origin, target, fov = EYE, TARGET, FOV
        for name, (pos, nrm, uv, f), bsdf in [
            ("sphere", sphere(), {"type": "diffuse", "reflectance": {"type": "bitmap", "filename": os.path.join(d, "texture.png"),
                                                                      "filter_type": "bilinear", "wrap_mode": "repeat"}}),
            ("ground", ground(), {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}}),
        ]:
            props = mi.Properties()
            props["bsdf"] = mi.load_dict(bsdf)
            m = mi.Mesh(name, len(pos), len(f), props=props, has_vertex_normals=True, has_vertex_texcoords=True)
            p = mi.traverse(m)
            p["vertex_positions"] = pos.astype(np.float32).ravel()
            p["vertex_normals"] = nrm.astype(np.float32).ravel()
            tc = uv.copy()
            tc[:, 1] = 1.0 - tc[:, 1]  # Mitsuba's v runs down the bitmap
            p["vertex_texcoords"] = tc.astype(np.float32).ravel()
            p["faces"] = f.astype(np.uint32).ravel()
            p.update()
            scene[name] = m
    scene["sensor"] = {
        "type": "perspective", "fov": fov, "fov_axis": "smaller",
        "to_world": T().look_at(origin=origin, target=target, up=[0, 1, 0]),
        "film": {"type": "hdrfilm", "width": a.size, "height": a.size, "rfilter": {"type": "box"}, "pixel_format": "rgb"},
        "sampler": {"type": "independent", "sample_count": a.spp},
    }
    return scene


def run_mitsuba(d, a, seed, to_world_deg, bare=False):
    import mitsuba as mi
    import numpy as np

    spp = a.spp if not bare else 16
    scene = mi.load_dict(mitsuba_scene(d, a, to_world_deg, bare))
    mi.render(scene, spp=1, seed=0)  # warm up (JIT, thread pool)
    c0, t0 = time.process_time(), time.perf_counter()
    img = mi.render(scene, spp=spp, seed=seed)
    img = np.array(img, dtype=np.float64)[..., :3]
    return img, time.perf_counter() - t0, time.process_time() - c0


def rmse(x, y):
    import numpy as np

    return float(np.sqrt(np.mean((x - y) ** 2)))


def save_png(path, img):
    import numpy as np

    c = np.clip(img, 0.0, 1.0)
    c = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    _images.png_write(path, (255 * c + 0.5).astype(np.uint8))


def main():
    _images.ensure(["mitsuba", "numpy"], ["mitsuba", "numpy"], __file__, "ENV_MITSUBA_REEXEC")
    import mitsuba as mi
    import numpy as np

    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--rotation", type=float, default=60.0)
    ap.add_argument("--check-only", action="store_true")
    ap.add_argument("--docs", action="store_true")
    ap.add_argument("--reuse", action="store_true", help="keep cgnodes' images of an earlier run")
    a = ap.parse_args()
    mi.set_variant(a.variant)
    d = os.path.join(ROOT, "target", "env_mitsuba")
    os.makedirs(d, exist_ok=True)
    write_obj(os.path.join(d, "sphere.obj"), sphere())
    write_obj(os.path.join(d, "ground.obj"), ground())
    _images.png_write(os.path.join(d, "texture.png"), texture())
    out = {"variant": a.variant, "mitsuba": mi.__version__, "size": a.size, "spp": a.spp, "rotation": a.rotation}

    # 1. The orientation of the sky: which to_world makes Mitsuba's bare sky ours?
    ours, _, _ = run_cgnodes(d, a, 1, bare=True)
    cands = {}
    for name, deg in [("rotation+180", a.rotation + 180), ("rotation", a.rotation),
                      ("-rotation+180", 180 - a.rotation), ("-rotation", -a.rotation)]:
        theirs, _, _ = run_mitsuba(d, a, 1, deg, bare=True)
        cands[name] = {"rmse": rmse(ours, theirs), "mean_ours": ours.mean(axis=(0, 1)).tolist(),
                       "mean_mitsuba": theirs.mean(axis=(0, 1)).tolist()}
    out["sky_orientation"] = cands
    best = min(cands, key=lambda k: cands[k]["rmse"])
    out["sky_orientation_best"] = best
    if a.check_only or best != "rotation+180":
        print(json.dumps(out, indent=1))
        return

    # 2. The scene, two seeds each.
    runs = {}
    for who in ["cgnodes", "mitsuba"]:
        for seed in [1, 2]:
            cached = os.path.join(d, f"{who}_{seed}.exr")
            if who == "cgnodes" and a.reuse and os.path.exists(cached):
                img = np.array(mi.Bitmap(cached), dtype=np.float64)[..., :3]
                secs = cpu = float("nan")
            elif who == "cgnodes":
                img, secs, cpu = run_cgnodes(d, a, seed)
            else:
                img, secs, cpu = run_mitsuba(d, a, seed, a.rotation + 180)
            mi.Bitmap(img.astype(np.float32)).write(os.path.join(d, f"{who}_{seed}.exr"))
            runs[(who, seed)] = img
            out[f"{who}_{seed}"] = {"wall_s": round(secs, 3), "cpu_s": round(cpu, 3),
                                    "mean_rgb": [round(float(x), 6) for x in img.mean(axis=(0, 1))]}
    c = (runs[("cgnodes", 1)] + runs[("cgnodes", 2)]) / 2
    m = (runs[("mitsuba", 1)] + runs[("mitsuba", 2)]) / 2
    mc, mm = c.mean(axis=(0, 1)), m.mean(axis=(0, 1))
    out["mean_rgb_cgnodes"] = [round(float(x), 6) for x in mc]
    out["mean_rgb_mitsuba"] = [round(float(x), 6) for x in mm]
    out["mean_rel_diff"] = [round(float(x), 5) for x in (mc - mm) / mm]
    r_cc = rmse(runs[("cgnodes", 1)], runs[("cgnodes", 2)])
    r_mm = rmse(runs[("mitsuba", 1)], runs[("mitsuba", 2)])
    r_cm = rmse(runs[("cgnodes", 1)], runs[("mitsuba", 1)])
    out["rmse_cgnodes_seeds"] = round(r_cc, 6)
    out["rmse_mitsuba_seeds"] = round(r_mm, 6)
    out["rmse_cgnodes_mitsuba"] = round(r_cm, 6)
    out["noise_floor"] = round(float(np.sqrt((r_cc ** 2 + r_mm ** 2) / 2)), 6)
    out["rmse_over_noise_floor"] = round(r_cm / out["noise_floor"], 4)
    # Where the difference lives: the sphere, the ground in and out of the shadow, the sky.
    if a.docs:
        os.makedirs(os.path.join(ROOT, "docs", "images"), exist_ok=True)
        save_png(os.path.join(ROOT, "docs", "images", "env_mitsuba_cgnodes.png"), c)
        save_png(os.path.join(ROOT, "docs", "images", "env_mitsuba_mitsuba.png"), m)
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
