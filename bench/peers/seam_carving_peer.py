#!/usr/bin/env python3
"""`seam_carve` against the PyPI package `seam-carving` (li-plus, numba-compiled DP):
removing 25 % of the columns of lena.png (512x512) and of a 1024x768 image (lena tiled with
its mirror images), with backward and with forward energy, width first.

Times: the peer's `seam_carving.resize` call (after a warm-up call, so numba's compilation is
not counted) against the node's own `time_ms`, each the median of three runs; both
single-threaded by nature (one seam after another).

Removed positions: the peer's seams come from its `carve._get_seams` (the set of input pixels
its resize removes), ours from the node's `seams` output (the input with removed pixels in
red). Both definitions are the same (Sobel gradient magnitude |Gx| + |Gy| with replicated
borders, or Rubinstein et al.'s forward costs with replicated borders; ties to the leftmost
candidate), but the peer takes the energy of an 8-bit grey image (`rgb @ [0.2125, 0.7154,
0.0721]` truncated to uint8, in float32), and cgnodes of the Rec. 709 luminance (0.2126,
0.7152, 0.0722) of the same bytes / 255 in f64 (the image loaded with color_space raw, so the
sRGB decoding is not a third difference). Two runs are compared: on the colour image, and on
the peer's own grey image given to both, where only the arithmetic differs (integers in
float32 against bytes / 255 in f64: equal-energy seams, frequent with integer energies, may be
broken differently, and one different seam changes all later ones).

    python3 bench/peers/seam_carving_peer.py     # needs target/release/cgnodes (or $CGNODES)

Installs `seam-carving` and `numpy` into target/peers-venv when they are missing.
"""
import os
import statistics
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _images  # noqa: E402

RUNS = int(os.environ.get("PEERS_RUNS", "3"))


def cases(np):
    lena = _images.png_read(os.path.join(_images.ROOT, "assets", "images", "lena.png"))[..., :3]
    yield "lena 512x512", lena
    if os.environ.get("PEERS_SMOKE"):
        return
    top = np.concatenate([lena, lena[:, ::-1]], axis=1)
    yield "1024x768", np.ascontiguousarray(np.concatenate([top, top[::-1][:256]], axis=0))


def ours(np, d, src, width, energy):
    _images.png_write(os.path.join(d, "src.png"), src)
    nodes = {
        "load": {"type": "image_load", "params": {"path": "src.png", "color_space": "raw"}},
        "carve": {
            "type": "seam_carve",
            "params": {"width": width, "height": src.shape[0], "energy": energy},
            "inputs": {"image": "load.image"},
        },
        "seams": {"type": "image_save", "params": {"path": "seams.png"}, "inputs": {"image": "carve.seams"}},
        "table": {"type": "table_write", "params": {"path": "t.csv"}, "inputs": {"value": "carve.table"}},
    }
    times, removed = [], None
    for _ in range(RUNS):
        out = _images.run_graph(d, nodes)
        times.append(_images.read_table(os.path.join(out, "t.csv"))[0]["time_ms"])
        s = _images.png_read(os.path.join(out, "seams.png"))[..., :3].astype(int)
        red = (s[..., 0] == 255) & (s[..., 1] == 0) & (s[..., 2] == 0)
        rgb = src if src.ndim == 3 else np.stack([src] * 3, axis=-1)
        removed = red & ~((rgb[..., 0] == 255) & (rgb[..., 1] == 0) & (rgb[..., 2] == 0))
    return statistics.median(times), removed


def main():
    _images.ensure(["seam_carving", "numpy"], ["seam-carving", "numpy"], __file__, "SEAM_PEER_REEXEC")
    import numpy as np
    import seam_carving
    from seam_carving import carve

    warm = np.zeros((20, 20, 3), np.uint8)
    for mode in ("backward", "forward"):
        seam_carving.resize(warm, (15, 20), energy_mode=mode, order="width-first")
    print(f"seam-carving (PyPI), numpy {np.__version__}, cgnodes {_images.cgnodes_bin()}, {os.cpu_count()} cores\n")
    print("| image | energy | cgnodes ms | seam-carving ms | cgnodes / peer | same removed pixels, colour | same removed pixels, peer's grey |")
    print("|---|---|---|---|---|---|---|")
    result = []
    for name, src in cases(np):
        h, w = src.shape[:2]
        width = w - w // 4
        for mode in ("backward", "forward"):
            peer_ms = []
            for _ in range(RUNS):
                t0 = time.perf_counter()
                seam_carving.resize(src, (width, h), energy_mode=mode, order="width-first")
                peer_ms.append((time.perf_counter() - t0) * 1e3)
            gray = carve._rgb2gray(src)
            agree = []
            with tempfile.TemporaryDirectory() as d:
                ms, mine = ours(np, d, src, width, mode)
                peer = carve._get_seams(gray, w - width, mode, None)
                agree.append((mine & peer).sum() / peer.sum())
                _, mine_g = ours(np, d, gray, width, mode)
                agree.append((mine_g & peer).sum() / peer.sum())
            pm = statistics.median(peer_ms)
            print(f"| {name} | {mode} | {ms:.0f} | {pm:.0f} | {ms / pm:.2f} | {agree[0]:.1%} | {agree[1]:.1%} |")
            result.append({"case": f"{name}, {mode} energy, 25 % of the columns", "ours_ms": ms, "peer_ms": pm,
                           "accuracy": {"same_removed_pixels_colour": float(agree[0]),
                                        "same_removed_pixels_peer_grey": float(agree[1])}})
    _images.result(result, peer_version=getattr(seam_carving, "__version__", "seam-carving"))


if __name__ == "__main__":
    main()
