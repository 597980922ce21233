#!/usr/bin/env python3
"""What the run report costs: each graph run with the report and with --no-report,
alternated over ROUNDS rounds in one process tree, as a user runs it (the cgnodes binary,
whole process). Writes bench/results/report_overhead.json (machine, commit, date, each
round's seconds, medians, ratio, extra milliseconds).

Usage: cargo build --release && python3 bench/report_overhead.py [--rounds N] [--bin PATH]
"""
import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _record  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# (name, graph, extra arguments): the README's graph, Tutte on a 44k-face mesh, a cloth
# frame range (three integrators, 60 frames) and an image graph.
CASES = [
    ("readme_tutte", "graphs/tutte_cotangent_circle.json", []),
    ("tutte_44k_faces", "bench/graphs/report_tutte_big.json", []),
    ("cloth_60_frames", "graphs/cloth_hang.json", ["--frames", "1..60"]),
    ("image_poisson", "graphs/poisson_seamless.json", []),
]


def run(binary, graph, extra, out, report):
    args = [binary, "run", os.path.join(ROOT, graph), "--out", out, "-q", *extra]
    if not report:
        args.append("--no-report")
    t = time.perf_counter()
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--bin", default=os.path.join(ROOT, "target/release/cgnodes"))
    a = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, graph, extra in CASES:
            with_r, without = [], []
            run(a.bin, graph, extra, os.path.join(tmp, "warm"), True)  # page cache warm
            for _ in range(a.rounds):
                with_r.append(run(a.bin, graph, extra, os.path.join(tmp, "r"), True))
                without.append(run(a.bin, graph, extra, os.path.join(tmp, "n"), False))
            mr, mn = statistics.median(with_r), statistics.median(without)
            row = {
                "case": name, "graph": graph, "args": extra,
                "with_report_s": with_r, "no_report_s": without,
                "median_with_report_s": mr, "median_no_report_s": mn,
                "ratio": mr / mn, "extra_ms": (mr - mn) * 1e3,
                # issue 62's bar: at most 1.10x, or at most 50 ms more, whichever is larger
                "meets_bar": mr <= max(1.10 * mn, mn + 0.050),
            }
            rows.append(row)
            print(f"{name:18s} with {mr*1e3:8.1f} ms  without {mn*1e3:8.1f} ms  "
                  f"ratio {mr/mn:5.2f}  +{(mr-mn)*1e3:6.1f} ms  {'ok' if row['meets_bar'] else 'over'}")
    _record.write("report_overhead", "python3 bench/report_overhead.py --rounds %d" % a.rounds, rounds=a.rounds, cases=rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
