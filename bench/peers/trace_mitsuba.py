#!/usr/bin/env python3
"""Mitsuba 3 peer for `cargo bench --bench trace`: renders mi.cornell_box() (256x256,
path integrator, max_depth 8, box filter) at a few spp, timed in-process around mi.render,
and writes the images to target/trace_bench/ with mitsuba.json for the Rust bench to score
against the same reference.

    python3 bench/peers/trace_mitsuba.py [--spp 4,16,64] [--variants scalar_rgb,llvm_ad_rgb]
                                         [--scene box|igea] [--igea PATH]

`--scene igea` adds the 154k-triangle igea scan (default
assets/meshes/igea_front.obj) standing in the box, white diffuse, scaled so its
largest extent is 0.8 with its box centre at (0, -0.2, 0.2), as `cargo bench --bench trace
-- --scene igea` builds it (Mitsuba computes its smooth vertex normals, ours come from the
60-degree crease rule, which on a scan is smooth everywhere but at sharp folds).

Installs `mitsuba` and `numpy` with pip if they are missing. llvm_ad_rgb needs LLVM
(Debian's libllvm19); a variant that fails to load is skipped and reported.
"""
import argparse, json, os, subprocess, sys, time

from _mitsuba import import_mitsuba, scene_dict

mi = import_mitsuba()


ap = argparse.ArgumentParser()
ap.add_argument("--spp", default="4,16,64")
ap.add_argument("--variants", default="scalar_rgb,llvm_ad_rgb")
ap.add_argument("--probe", default=None, help=argparse.SUPPRESS)
ap.add_argument("--scene", default="box", choices=["box", "igea"])
ap.add_argument("--igea", default="assets/meshes/igea_front.obj")
ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "..", "target", "trace_bench"))
a = ap.parse_args()
if a.probe:  # child process: does this variant render at all? (LLVM may abort the process)
    mi.set_variant(a.probe)
    mi.render(mi.load_dict(mi.cornell_box()), spp=1)
    sys.exit(0)
os.makedirs(a.out, exist_ok=True)
# Runs of other scenes or variants stay in mitsuba.json; a rerun replaces its own entries.
try:
    with open(os.path.join(a.out, "mitsuba.json")) as f:
        runs = json.load(f)["runs"]
except (OSError, ValueError, KeyError):
    runs = []
for variant in a.variants.split(","):
    probe = subprocess.run([sys.executable, __file__, "--probe", variant], capture_output=True, text=True)
    if probe.returncode != 0:
        err = (probe.stderr.strip().splitlines() or ["?"])[0]
        print(f"{variant}: unavailable ({err})")
        continue
    mi.set_variant(variant)
    scene = mi.load_dict(scene_dict(mi, a.scene, a.igea))
    mi.render(scene, spp=1, seed=0)  # warm up (JIT, thread pool)
    for spp in [int(s) for s in a.spp.split(",")]:
        c0 = time.process_time()
        t0 = time.perf_counter()
        img = mi.render(scene, spp=spp, seed=1)
        if hasattr(img, "numpy"):
            img.numpy()  # force evaluation for the JIT variants
        secs = time.perf_counter() - t0
        cpu = time.process_time() - c0
        name = f"mitsuba_{variant}_{a.scene}_{spp}.exr"
        mi.Bitmap(img).write(os.path.join(a.out, name))
        mpaths = 256 * 256 * spp / secs / 1e6
        print(f"{variant} {a.scene} {spp:5d} spp: {secs:7.3f} s ({cpu:.2f} s CPU), {mpaths:.2f} Mpaths/s, "
              f"{256 * 256 * spp / max(cpu, 1e-9) / 1e6:.2f} Mpaths per CPU-second")
        runs = [r for r in runs if (r["variant"], r.get("scene", "box"), r["spp"]) != (variant, a.scene, spp)]
        runs.append({"variant": variant, "scene": a.scene, "spp": spp, "seconds": secs, "cpu_seconds": cpu, "exr": name})
        with open(os.path.join(a.out, "mitsuba.json"), "w") as f:
            json.dump({"mitsuba": getattr(mi, "__version__", "?"), "runs": runs}, f, indent=1)
