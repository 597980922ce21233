#!/usr/bin/env python3
"""scikit-image's thin-plate spline warp against cgnodes' `image_warp` (issue 24).

Usage: warp_skimage.py [CGNODES_BINARY] [RUNS]

On a 1024x1024 RGB image (a smooth colour ramp under a 32-pixel checkerboard, made here with
numpy) and 32 control points (seeded random positions, moved by up to 24 px), times
- scikit-image: `ThinPlateSplineTransform.estimate(q, p)` (the inverse map, output -> input)
  plus `skimage.transform.warp(image, tform, order=1, mode="edge")`;
- cgnodes: `image_warp` with method rbf, kernel thin_plate, mapping inverse, the node's own
  time (its table's `time` column: fit + map + sampling, no file I/O) and the wall time of the
  whole `cgnodes run` (PNG decode and encode included);
and compares the two images where ours is valid (alpha 1): largest difference per channel in
1/255 units, against scikit-image's result and against scikit-image's `warp` driven by the
exact thin-plate spline (a float64 numpy solve of the same system), since scikit-image's own
fit misses its control points slightly (reported as `skimage_residual_px`). Both interpolate the stored 8-bit values (the graph loads with color_space raw
and saves with gamma 1), and scikit-image's pixel centres are at integers, ours at i + 0.5,
so its control points are ours minus 0.5. Prints one JSON object.

Needs scikit-image; when it is missing the script installs it into target/peers-venv (PyPI)
and re-runs itself there.
"""
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import _images  # noqa: E402  (the peers' virtual environment and the cgnodes binary)


def main():
    _images.ensure(["skimage", "numpy"], ["scikit-image", "numpy"], __file__, "WARP_SKIMAGE_REEXEC")
    import numpy as np
    import skimage
    from skimage import io
    from skimage.transform import ThinPlateSplineTransform, warp

    cg = sys.argv[1] if len(sys.argv) > 1 else _images.cgnodes_bin()
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    n, size = 32, 1024
    rng = np.random.default_rng(24)
    y, x = np.mgrid[0:size, 0:size]
    checker = ((x // 32 + y // 32) % 2).astype(np.float64)
    img = np.stack([x / size, y / size, 0.5 + 0.5 * np.sin(x / 50.0) * np.cos(y / 70.0)], axis=-1)
    img = (255 * (0.6 * img + 0.4 * checker[..., None])).round().astype(np.uint8)
    p = rng.uniform(64, size - 64, size=(n, 2))
    q = p + rng.uniform(-24, 24, size=(n, 2))

    # scikit-image: the map from output to input coordinates (its centres at integers).
    imgf = img.astype(np.float64) / 255.0
    t_sk = []
    for _ in range(runs):
        t0 = time.perf_counter()
        tform = ThinPlateSplineTransform()
        tform.estimate(q - 0.5, p - 0.5)
        out_sk = warp(imgf, tform, order=1, mode="edge")
        t_sk.append(time.perf_counter() - t0)

    with tempfile.TemporaryDirectory() as d:
        io.imsave(os.path.join(d, "in.png"), img, check_contrast=False)
        graph = {
            "format": "cgnodes-graph",
            "version": 1,
            "nodes": {
                "load": {"type": "image_load", "params": {"path": "in.png", "color_space": "raw"}},
                "warp": {
                    "type": "image_warp",
                    "params": {
                        "source_points": p.tolist(),
                        "target_points": q.tolist(),
                        "method": "rbf",
                        "kernel": "thin_plate",
                        "mapping": "inverse",
                    },
                    "inputs": {"image": "load.image"},
                },
                "save": {"type": "image_save", "params": {"path": "out.png", "gamma": 1.0},
                         "inputs": {"image": "warp.image"}},
                "table": {"type": "table_write", "params": {"path": "table.csv"},
                          "inputs": {"value": "warp.table"}},
            },
        }
        gpath = os.path.join(d, "warp.json")
        with open(gpath, "w") as f:
            json.dump(graph, f)
        t_node, t_wall = [], []
        for r in range(runs):
            out = os.path.join(d, "out%d" % r)
            t0 = time.perf_counter()
            subprocess.run([cg, "run", "-q", gpath, "--out", out], check=True)
            t_wall.append(time.perf_counter() - t0)
            with open(os.path.join(out, "table.csv")) as f:
                head, row = f.read().split("\n")[:2]
            t_node.append(float(dict(zip(head.split(","), row.split(",")))["time"]))
        ours = io.imread(os.path.join(d, "out%d" % (runs - 1), "out.png")).astype(np.float64)
    # scikit-image's own fit does not interpolate exactly: its residual at the control points
    # and its distance from the exact thin-plate spline (a float64 numpy solve of the same
    # system), and the same `warp` driven by the exact spline, to separate map from sampling.
    qs, ps = q - 0.5, p - 0.5
    U = lambda d2: np.where(d2 > 0, 0.5 * d2 * np.log(np.where(d2 > 0, d2, 1.0)), 0.0)
    m = np.zeros((n + 3, n + 3))
    m[:n, :n] = U(((qs[:, None] - qs[None]) ** 2).sum(-1))
    aff = np.hstack([qs, np.ones((n, 1))])
    m[:n, n:], m[n:, :n] = aff, aff.T
    sol = np.linalg.solve(m, np.vstack([ps, np.zeros((3, 2))]))

    def exact(xy):
        return U(((xy[:, None] - qs[None]) ** 2).sum(-1)) @ sol[:n] + np.hstack([xy, np.ones((len(xy), 1))]) @ sol[n:]

    probe = rng.uniform(0, size, size=(2000, 2))
    out_exact = warp(imgf, exact, order=1, mode="edge")
    valid = ours[..., 3] == 255
    diff_exact = np.abs(ours[..., :3] - np.round(out_exact * 255.0))[valid]

    diff = np.abs(ours[..., :3] - np.round(out_sk * 255.0))[valid]
    res = {
        "image": [size, size],
        "control_points": n,
        "runs": runs,
        "skimage_version": skimage.__version__,
        "skimage_s_median": float(np.median(t_sk)),
        "cgnodes_node_s_median": float(np.median(t_node)),
        "cgnodes_run_wall_s_median": float(np.median(t_wall)),
        "ratio_node_to_skimage": float(np.median(t_node) / np.median(t_sk)),
        "valid_pixels": int(valid.sum()),
        "max_diff_255": float(diff.max()),
        "pixels_over_1_255": int((diff.max(axis=1) > 1.0).sum()),
        "skimage_residual_px": float(np.abs(tform(qs) - ps).max()),
        "skimage_vs_exact_tps_px": float(np.abs(tform(probe) - exact(probe)).max()),
        "max_diff_255_vs_exact_tps_warp": float(diff_exact.max()),
        "pixels_over_1_255_vs_exact_tps_warp": int((diff_exact.max(axis=1) > 1.0).sum()),
    }
    print(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
