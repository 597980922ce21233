#!/usr/bin/env python3
"""`image_svd` against numpy's `linalg.svd` (LAPACK gesdd through numpy's BLAS/LAPACK) on one
1024x1024 channel: lena's grey (Rec. 709 luma of the sRGB bytes) tiled 2x2 with mirror images,
so the matrix is full rank, written as an 8-bit grey PNG and read by both sides as bytes / 255.

Rank 50 by cgnodes' full SVD (faer's thin SVD), cgnodes' randomized SVD (Halko et al. 2011,
oversampling 10, 2 power iterations) and numpy's thin SVD; times are medians of three runs:
cgnodes' the node's own `time_ms` (channel extraction, SVD, reconstruction, PSNR), numpy's the
`svd` call plus the rank-50 reconstruction. cgnodes runs on one thread (`--threads 1`, which
also holds faer's kernels to one thread); numpy uses its BLAS's threads (every core) unless
OPENBLAS_NUM_THREADS=1 is set.

    python3 bench/peers/svd_numpy.py      # needs target/release/cgnodes (or $CGNODES)

Installs `numpy` into target/peers-venv when it is missing.
"""
import os
import statistics
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _images  # noqa: E402

RANK, RUNS = 50, int(os.environ.get("PEERS_RUNS", "3"))


def main():
    _images.ensure(["numpy"], ["numpy"], __file__, "SVD_NUMPY_REEXEC")
    import numpy as np

    lena = _images.png_read(os.path.join(_images.ROOT, "assets", "images", "lena.png")).astype(float)
    g = np.clip(np.round(lena[..., :3] @ [0.2126, 0.7152, 0.0722]), 0, 255)
    tile = np.block([[g, g[:, ::-1]], [g[::-1], g[::-1, ::-1]]]).astype(np.uint8)
    a = tile.astype(np.float64) / 255.0
    print(f"numpy {np.__version__}, cgnodes {_images.cgnodes_bin()}, {os.cpu_count()} cores, "
          f"a {a.shape[0]}x{a.shape[1]} channel, rank {RANK}\n")
    np_ms, np_psnr = [], 0.0
    for _ in range(RUNS):
        t0 = time.perf_counter()
        u, s, vt = np.linalg.svd(a, full_matrices=False)
        ak = (u[:, :RANK] * s[:RANK]) @ vt[:RANK]
        np_ms.append((time.perf_counter() - t0) * 1e3)
        np_psnr = -10 * np.log10(np.mean((ak - a) ** 2))
    with tempfile.TemporaryDirectory() as d:
        _images.png_write(os.path.join(d, "a.png"), tile)
        nodes = {"load": {"type": "image_load", "params": {"path": "a.png", "color_space": "raw"}}}
        for m in ("full", "randomized"):
            nodes[m] = {
                "type": "image_svd",
                "params": {"rank": RANK, "method": m, "grayscale": True, "oversample": 10, "power_iterations": 2},
                "inputs": {"image": "load.image"},
            }
            nodes[m + "_t"] = {"type": "table_write", "params": {"path": m + ".csv"}, "inputs": {"value": m + ".table"}}
        rows = {"full": [], "randomized": []}
        for _ in range(RUNS):
            out = _images.run_graph(d, nodes)
            for m in rows:
                rows[m].append(_images.read_table(os.path.join(out, m + ".csv"))[0])
    full_ms = statistics.median(r["time_ms"] for r in rows["full"])
    rand_ms = statistics.median(r["time_ms"] for r in rows["randomized"])
    fp, rp = rows["full"][0]["psnr"], rows["randomized"][0]["psnr"]
    print("| | ms (median of 3) | PSNR dB at rank 50 |")
    print("|---|---|---|")
    print(f"| numpy linalg.svd + reconstruction | {statistics.median(np_ms):.1f} | {np_psnr:.4f} |")
    print(f"| cgnodes full | {full_ms:.1f} | {fp:.4f} |")
    print(f"| cgnodes randomized (p = 10, q = 2) | {rand_ms:.1f} | {rp:.4f} |")
    print(f"\nfull / numpy = {full_ms / statistics.median(np_ms):.2f} (goal <= 1.5); "
          f"full / randomized = {full_ms / rand_ms:.1f} (goal >= 5); "
          f"PSNR full - randomized = {fp - rp:.4f} dB (goal <= 0.1)")
    npm = statistics.median(np_ms)
    _images.result([
        {"case": f"{a.shape[0]}x{a.shape[1]} channel, rank {RANK}, full SVD (faer)", "ours_ms": full_ms, "peer_ms": npm,
         "accuracy": {"psnr_ours_db": fp, "psnr_peer_db": float(np_psnr)}},
        {"case": f"{a.shape[0]}x{a.shape[1]} channel, rank {RANK}, randomized SVD (p = 10, q = 2)", "ours_ms": rand_ms,
         "peer_ms": npm, "accuracy": {"psnr_ours_db": rp, "psnr_peer_db": float(np_psnr)}},
    ], peer_version="numpy " + np.__version__)


if __name__ == "__main__":
    main()
