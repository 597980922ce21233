#!/usr/bin/env python3
"""`rpca` against a plain numpy implementation of the same ADMM iteration (the course's:
singular-value thresholding with numpy's thin SVD, soft thresholding, Y += rho (M - L - S))
at equal iteration counts, on Candès et al.'s synthetic case: 500x500, rank 25 (L = X Y^T /
sqrt(n), Gaussian X and Y), 5 % of the entries corrupted by values uniform in [-50, 50].

Both run exactly ITERATIONS iterations (tolerance 1e-15 is never reached) with lambda =
1/sqrt(500) and rho = m n / (4 ||M||_1). cgnodes reads M from a CSV and reports the time of
its iterations in its log (`time_ms`, the CSV reading excluded); numpy's time is the loop's.
The two results are compared entry by entry, and both against the true L and S.

    python3 bench/peers/rpca_numpy.py [ITERATIONS]   # default 60; needs target/release/cgnodes

Installs `numpy` into target/peers-venv when it is missing.
"""
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _images  # noqa: E402


def admm(np, m, iterations):
    lam = 1 / np.sqrt(max(m.shape))
    rho = m.size / (4 * np.abs(m).sum())
    s = np.zeros_like(m)
    y = np.zeros_like(m)
    for _ in range(iterations):
        u, sig, vt = np.linalg.svd(m - s + y / rho, full_matrices=False)
        sig = np.maximum(sig - 1 / rho, 0)
        k = int((sig > 0).sum())
        low = (u[:, :k] * sig[:k]) @ vt[:k]
        t = m - low + y / rho
        s = np.sign(t) * np.maximum(np.abs(t) - lam / rho, 0)
        y += rho * (m - low - s)
    return low, s


def main():
    _images.ensure(["numpy"], ["numpy"], __file__, "RPCA_NUMPY_REEXEC")
    import numpy as np

    iterations = int(sys.argv[1]) if len(sys.argv) > 1 else 60
    n, r = 500, 25
    rng = np.random.default_rng(0)
    l0 = rng.standard_normal((n, r)) @ rng.standard_normal((r, n)) / np.sqrt(n)
    s0 = np.zeros((n, n))
    hit = rng.random((n, n)) < 0.05
    s0[hit] = rng.uniform(-50, 50, hit.sum())
    m = l0 + s0
    print(f"numpy {np.__version__}, cgnodes {_images.cgnodes_bin()}, {os.cpu_count()} cores, "
          f"{n}x{n} rank {r}, {hit.mean():.3%} corrupted, {iterations} iterations\n")
    t0 = time.perf_counter()
    nl, ns = admm(np, m, iterations)
    np_ms = (time.perf_counter() - t0) * 1e3
    with tempfile.TemporaryDirectory() as d:
        np.savetxt(os.path.join(d, "m.csv"), m, delimiter=",", fmt="%.17g")
        nodes = {
            "rpca": {"type": "rpca", "params": {"matrix": "m.csv", "tolerance": 1e-15, "max_iterations": iterations}},
            "log": {"type": "table_write", "params": {"path": "log.csv"}, "inputs": {"value": "rpca.log"}},
            "l": {"type": "table_write", "params": {"path": "l.csv"}, "inputs": {"value": "rpca.low_rank_matrix"}},
            "s": {"type": "table_write", "params": {"path": "s.csv"}, "inputs": {"value": "rpca.sparse_matrix"}},
        }
        out = _images.run_graph(d, nodes)
        log = _images.read_table(os.path.join(out, "log.csv"))
        cl = np.loadtxt(os.path.join(out, "l.csv"), delimiter=",", skiprows=1)
        cs = np.loadtxt(os.path.join(out, "s.csv"), delimiter=",", skiprows=1)
    ours_ms = log[-1]["time_ms"]
    rel = lambda a, b: np.linalg.norm(a - b) / np.linalg.norm(b)  # noqa: E731
    print("| | ms | ms / iteration | rel. error of L | rel. error of S |")
    print("|---|---|---|---|---|")
    print(f"| numpy | {np_ms:.0f} | {np_ms / iterations:.1f} | {rel(nl, l0):.2e} | {rel(ns, s0):.2e} |")
    print(f"| cgnodes | {ours_ms:.0f} | {ours_ms / len(log):.1f} | {rel(cl, l0):.2e} | {rel(cs, s0):.2e} |")
    print(f"\ncgnodes / numpy = {ours_ms / np_ms:.2f} (goal <= 0.5) at {len(log)} iterations each; "
          f"L differs from numpy's by {rel(cl, nl):.1e}, S by {rel(cs, ns):.1e} (relative); "
          f"last primal / dual residual {log[-1]['primal']:.1e} / {log[-1]['dual']:.1e}")
    _images.result([{"case": f"{n}x{n}, rank {r}, 5 % corrupted, {iterations} ADMM iterations", "ours_ms": ours_ms,
                     "peer_ms": np_ms,
                     "accuracy": {"rel_error_L_ours": float(rel(cl, l0)), "rel_error_L_peer": float(rel(nl, l0)),
                                  "rel_diff_L_ours_vs_peer": float(rel(cl, nl))}}],
                   peer_version="numpy " + np.__version__)


if __name__ == "__main__":
    main()
