#!/usr/bin/env python3
"""`poisson_blend` against OpenCV's `cv2.seamlessClone` (NORMAL_CLONE = seamless, MIXED_CLONE =
mixed) on the course's bear pasted into NewBackGround.jpg and on a 1-megapixel paste (both
images upscaled, the whole source rectangle less a 2-pixel frame as the mask).

For each case and mode, cgnodes runs one graph with several `poisson_blend` nodes that paste
the same mask at twelve offsets, each into the previous paste's result (a chain, so the
nodes run one after another with all threads, like OpenCV's calls; OpenCV's pastes are
chained the same way): the first factors the Poisson matrix (or builds the multigrid
hierarchy), the others reuse it (their `table` says `reused = 1`), except where `solver: auto`
switches an irregular mask from multigrid to Cholesky (after three pastes of the course
mask, six of the ellipse: one more factorization). "first" is the first paste, "reused" the
median of the last four (a drag's steady state); the solver column lists each paste's
solver and iterations. The timed graph has no writer nodes: a writer of one paste's table or
image would run on the other core while the next paste runs (and every written file is synced
to disk), where OpenCV's calls are timed alone. A second run of the same graph with the writers gives the tables (solver,
iterations, residual) and the images compared.

Each chain starts after a warm-up paste, the first of the process ("cold first", seamless in
both modes): Ω eroded by one pixel (another shape), with the target's own pixels as the
source, so that its result is the target again and the timed chain starts from the same image
as OpenCV's. The timed first paste is then a new shape in a running process, as OpenCV's
calls are (its first call of the process, printed below the table, is often slower than the
rest). cgnodes gets as many threads as OpenCV uses (`cv2.getNumThreads()`), or `--threads N`
for both. cgnodes' times are each paste node's wall
time in the timed run's profile (`--profile-json`): the node's work (checks, right-hand side,
factorization or cache lookup, solve, the output image) plus the runtime's bookkeeping around
it (0.02 ms); OpenCV's the `seamlessClone` call on decoded arrays (median of the offsets). The
mean difference is between the two 8-bit results over the mask, in 8-bit units: OpenCV solves
on sRGB-encoded bytes with its own solver and boundary (it also drops the mask's outer pixel
ring), cgnodes on linear values, so the two differ by design.

    python3 bench/peers/poisson_opencv.py [--threads N]   # needs target/release/cgnodes (or $CGNODES)

$POISSON_SOLVER (auto, cholesky, multigrid) sets the node's `solver` parameter (unset: the
parameter is not written, so binaries from before it existed run too).

Installs `opencv-python-headless` and `numpy` into target/peers-venv when they are missing.
"""
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import _images  # noqa: E402  (the peers' virtual environment and the cgnodes binary)


def cases(cv2, np):
    img = os.path.join(ROOT, "assets", "images")
    bear = cv2.imread(os.path.join(img, "BearInWater.jpg"))
    sea = cv2.imread(os.path.join(img, "NewBackGround.jpg"))
    mask = cv2.imread(os.path.join(img, "BearInWater_mask.png"), cv2.IMREAD_GRAYSCALE)
    yield "course (14.9k px)", sea, bear, mask, [
        (62, 162), (40, 150), (90, 170), (20, 140), (100, 160), (50, 155),
        (80, 165), (30, 145), (70, 158), (45, 152), (85, 168), (35, 147),
    ]
    big_sea = cv2.resize(sea, (1600, 1200), interpolation=cv2.INTER_CUBIC)
    big_bear = cv2.resize(bear, (1200, 900), interpolation=cv2.INTER_CUBIC)
    big_mask = np.zeros((900, 1200), np.uint8)
    big_mask[2:-2, 2:-2] = 255
    offsets = [
        (200, 150), (210, 160), (190, 140), (220, 170), (180, 130), (205, 155),
        (195, 145), (215, 165), (185, 135), (212, 162), (198, 148), (208, 158),
    ]
    if os.environ.get("PEERS_SMOKE"):
        return
    yield "1 megapixel rectangle (1.07M px)", big_sea, big_bear, big_mask, offsets
    # the same paste through an ellipse inscribed in the source: an irregular Ω of 0.84M px
    ellipse = np.zeros((900, 1200), np.uint8)
    cv2.ellipse(ellipse, (600, 450), (597, 447), 0, 0, 360, 255, -1)
    yield "1 megapixel ellipse (0.84M px)", big_sea, big_bear, ellipse, offsets


def opencv_paste(cv2, target, source, mask, off, flag):
    """One `seamlessClone` call and its time in ms."""
    x, y, w, h = cv2.boundingRect(mask)
    # OpenCV centres the mask's bounding box on `p`: its top-left lands at p - (w/2, h/2)
    p = (off[0] + x + w // 2, off[1] + y + h // 2)
    # copies: seamlessClone may write into its inputs (the mask shrank call after call)
    source, target, mask = source.copy(), target.copy(), mask.copy()
    t0 = time.perf_counter()
    out = cv2.seamlessClone(source, target, mask, p, flag)
    return out, (time.perf_counter() - t0) * 1e3


def cgnodes_pastes(cv2, np, d, target, source, mask, offsets, mode, threads):
    """The chain of pastes in one cgnodes process, after a warm-up paste (see the module
    comment); returns the warm-up's table row and one row (with the 8-bit image) per paste."""
    cv2.imwrite(os.path.join(d, "target.png"), target)
    cv2.imwrite(os.path.join(d, "source.png"), source)
    cv2.imwrite(os.path.join(d, "mask.png"), mask)
    # the warm-up: Ω eroded by one pixel (another shape, so the first timed paste still
    # builds its own hierarchy or factor), the target's own pixels under it as the source
    # (so its result is the target again, up to the solver's residual)
    ox, oy = offsets[0]
    h, w = mask.shape
    crop = target[oy:oy + h, ox:ox + w]
    warm_source = np.zeros_like(source)  # Ω and its neighbours lie inside the target
    warm_source[:crop.shape[0], :crop.shape[1]] = crop
    cv2.imwrite(os.path.join(d, "warm_source.png"), warm_source)
    cv2.imwrite(os.path.join(d, "warm_mask.png"), cv2.erode(mask, np.ones((3, 3), np.uint8)))
    nodes = {
        "t": {"type": "image_load", "params": {"path": "target.png"}},
        "s": {"type": "image_load", "params": {"path": "source.png"}},
        "m": {"type": "image_load", "params": {"path": "mask.png", "color_space": "raw"}},
        "ws": {"type": "image_load", "params": {"path": "warm_source.png"}},
        "wm": {"type": "image_load", "params": {"path": "warm_mask.png", "color_space": "raw"}},
        "warm": {
            "type": "poisson_blend",
            "params": {"offset": [float(ox), float(oy)], "mode": "seamless"},
            "inputs": {"target": "t.image", "source": "ws.image", "mask": "wm.image"},
        },
    }
    writers = {
        "ww": {"type": "table_write", "params": {"path": "warm.csv"}, "inputs": {"value": "warm.table"}},
    }
    for i, (ox, oy) in enumerate(offsets):
        nodes[f"b{i}"] = {
            "type": "poisson_blend",
            "params": {"offset": [float(ox), float(oy)], "mode": mode},
            "inputs": {"target": f"b{i - 1}.image" if i else "warm.image", "source": "s.image", "mask": "m.image"},
        }
        if os.environ.get("POISSON_SOLVER"):
            nodes[f"b{i}"]["params"]["solver"] = os.environ["POISSON_SOLVER"]
        writers[f"w{i}"] = {
            "type": "table_write", "params": {"path": f"t{i}.csv"}, "inputs": {"value": f"b{i}.table"},
        }
        writers[f"i{i}"] = {
            "type": "image_save", "params": {"path": f"out{i}.png"}, "inputs": {"image": f"b{i}.image"},
        }

    def run(name, nodes, extra=()):
        g = os.path.join(d, f"{name}.json")
        with open(g, "w") as f:
            json.dump({"format": "cgnodes-graph", "version": 1, "nodes": nodes}, f)
        out = os.path.join(d, name)
        cmd = [_images.cgnodes_bin(), "run", g, "--out", out, "--threads", str(threads), *extra]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit(f"cgnodes failed on {g}:\n{r.stderr}")
        return out

    # timed without writers (see the module comment): the last paste as the target, the
    # times from the profile; the same graph with the writers gives the tables and images
    profile = os.path.join(d, "profile.json")
    run("timed", nodes, ["--target", f"b{len(offsets) - 1}", "--profile-json", profile])
    with open(profile) as f:
        ms = {n["id"]: n["ms"] for n in json.load(f)[0]["nodes"]}
    images = run("images", {**nodes, **writers})

    def row(name, node):
        with open(os.path.join(images, name)) as f:
            r = {k: float(v) for k, v in next(csv.DictReader(f)).items()}
        r["time_ms"] = ms[node]
        return r

    rows = []
    for i in range(len(offsets)):
        rows.append(row(f"t{i}.csv", f"b{i}"))
        rows[-1]["image"] = cv2.imread(os.path.join(images, f"out{i}.png"))
    return row("warm.csv", "warm"), rows


def main():
    _images.ensure(["cv2", "numpy"], ["opencv-python-headless", "numpy"], __file__, "POISSON_OPENCV_REEXEC")
    import cv2
    import numpy as np

    threads = cv2.getNumThreads()
    if "--threads" in sys.argv:
        threads = int(sys.argv[sys.argv.index("--threads") + 1])
        cv2.setNumThreads(threads)
    print(f"OpenCV {cv2.__version__} ({cv2.getNumThreads()} threads), cgnodes {_images.cgnodes_bin()} ({threads} threads), {os.cpu_count()} cores; pastes chained\n")
    print("| case | mode | pixels | cgnodes solver | cgnodes cold first ms | cgnodes first ms | cgnodes reused ms | OpenCV ms | first / OpenCV | reused / OpenCV | mean diff (8-bit) | residual |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    opencv_first = None
    result = []
    for name, target, source, mask, offsets in cases(cv2, np):
        for mode, flag in (("seamless", cv2.NORMAL_CLONE), ("mixed", cv2.MIXED_CLONE)):
            cv_times, cv_out = [], []
            base = target
            for off in offsets:
                out, ms = opencv_paste(cv2, base, source, mask, off, flag)
                cv_times.append(ms)
                if opencv_first is None:
                    opencv_first = ms
                cv_out.append(out)
                base = out
            with tempfile.TemporaryDirectory() as d:
                warm, rows = cgnodes_pastes(cv2, np, d, target, source, mask, offsets, mode, threads)
            factored = [i for i, r in enumerate(rows) if r["reused"] == 0.0]
            if factored[:1] != [0] or len(factored) > 2:
                sys.exit(f"expected one factorization (two with the switch), got reused = {[r['reused'] for r in rows]}")
            first = rows[:1]
            reused = rows[-4:]
            diffs = []
            for r, o, off in zip(rows, cv_out, offsets):
                region = np.zeros(target.shape[:2], bool)
                ys, xs = np.nonzero(mask > 127)
                region[ys + off[1], xs + off[0]] = True
                diffs.append(np.abs(r["image"].astype(float) - o.astype(float))[region].mean())

            def name_of(r):
                if r.get("multigrid") == 1.0:
                    return f"MG {int(r['iterations'])} it."
                return "sine transform" if r.get("sine_transform") == 1.0 else "Cholesky"

            names = [name_of(r) for r in rows]
            solver = names[0] if len(set(names)) == 1 else ", ".join(names)
            cv_ms = statistics.median(cv_times)
            re_ms = statistics.median(r["time_ms"] for r in reused)
            print(
                f"| {name} | {mode} | {int(rows[0]['pixels'])} | {solver} | {warm['time_ms']:.1f} | {first[0]['time_ms']:.1f} | {re_ms:.1f} | {cv_ms:.1f} "
                f"| {first[0]['time_ms'] / cv_ms:.2f} | {re_ms / cv_ms:.2f} | {statistics.mean(diffs):.2f} "
                f"| {max(r['residual'] for r in rows):.1e} |"
            )
            # the first paste (a new mask shape: Ω found, hierarchy or factor built) and the
            # reused ones, each against OpenCV's median call of the same round
            result.append({"case": f"{name}, {mode}, first paste (new mask shape)",
                           "ours_ms": first[0]["time_ms"], "peer_ms": cv_ms,
                           "accuracy": {"mean_abs_diff_8bit": float(diffs[0]),
                                        "solver_ours": names[0],
                                        "residual_ours": first[0]["residual"]}})
            result.append({"case": f"{name}, {mode}, {len(offsets)} chained pastes (median paste, factor reused)",
                           "ours_ms": re_ms, "peer_ms": cv_ms,
                           "accuracy": {"mean_abs_diff_8bit": float(statistics.mean(diffs)),
                                        "max_residual_ours": max(r["residual"] for r in rows)}})
    print(f"\nOpenCV's first call of the process (the course mask, seamless): {opencv_first:.1f} ms")
    _images.result(result, peer_version="opencv-python-headless " + cv2.__version__, threads=threads)


if __name__ == "__main__":
    main()
