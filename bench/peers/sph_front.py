"""The dam-break front error as `compare_series` computes it (nodes/metrics/compare_series.rs
with error_in x, anchor (1.19, 1.44), min_y 1.44): the simulated front history (T, Z) is
shifted in T so that it reaches Z = 1.44 at T = 1.19 (Martin & Moyce's own anchor), then for
every row of bench/graphs/martin_moyce_front_TZ.csv with Z >= 1.44 the relative error of the
T at which the simulation first reaches that Z; the result is their root mean square. Shared
by bench/sweeps/sph_dam_break.sh and bench/peers/compare.py (SPlisHSPlasH's front)."""
import csv
import math
import os

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))


def reference():
    path = os.path.join(ROOT, "bench/graphs/martin_moyce_front_TZ.csv")
    return [(float(r["T"]), float(r["Z"])) for r in csv.DictReader(
        ln for ln in open(path) if not ln.startswith("#"))]


def first_x_reaching(s, y):
    if s[0][1] >= y:
        return s[0][0]
    for a, b in zip(s, s[1:]):
        if a[1] < y <= b[1]:
            return a[0] + (b[0] - a[0]) * (y - a[1]) / (b[1] - a[1])
    return None


def front_error(sim, ref=None):
    """RMS relative error in T of a front history [(T, Z), ...]; None if it never reaches
    Z = 1.44."""
    ref = ref or reference()
    s = sorted(sim)
    t = first_x_reaching(s, 1.44)
    if t is None:
        return None
    s = [(x + 1.19 - t, z) for x, z in s]
    errs = []
    for xr, yr in ref:
        if yr < 1.44:
            continue
        xs = first_x_reaching(s, yr)
        if xs is not None:
            errs.append((xs - xr) / xr)
    return math.sqrt(sum(e * e for e in errs) / len(errs)) if errs else None
