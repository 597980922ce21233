#!/usr/bin/env bash
# sph_dam_break: overlays SPlisHSPlasH's DFSPH (PyPI pysplishsplash, bench/peers/sph_splishsplash.py,
# same tank, column, CFL 0.4 and Akinci boundary; viscosity off) on the sweep's chart. For each
# particle radius it runs the peer to T = 3.5, scores its front exactly as the sweep's
# compare_series node does (error in T against bench/graphs/martin_moyce_front_TZ.csv for
# Z >= 1.44, time shifted so that T = 1.19 at Z = 1.44), writes
# docs/charts/sph_dam_break_splishsplash.csv with the sweep's column names and redraws
# docs/charts/sph_dam_break.svg with both CSVs. The Python is $SPH_PEER_PYTHON (default python3);
# without pysplishsplash the step is skipped and the sweep's own chart stays.
set -euo pipefail
py=${SPH_PEER_PYTHON:-python3}
peer_csv=docs/charts/sph_dam_break_splishsplash.csv
export LD_PRELOAD=/lib/x86_64-linux-gnu/libGLdispatch.so.0
# SPlisHSPlasH is OpenMP-parallel; with the default spin-waiting its threads lose 4-5x to other
# jobs on a shared machine (measured: 6.8 s against 1.5 s at r = 0.01), so wait passively unless told.
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}
if ! "$py" -c 'import pysplishsplash, numpy' 2>/dev/null; then
  echo "sph_dam_break.sh: pysplishsplash (and numpy) not importable by $py; skipping the SPlisHSPlasH overlay"
  echo "  (pip install pysplishsplash numpy, or set SPH_PEER_PYTHON to a Python that has them)"
  exit 0
fi
"$py" - "$peer_csv" <<'PY'
import csv, json, math, subprocess, sys
out = sys.argv[1]
py = sys.executable
ref = [(float(r["T"]), float(r["Z"])) for r in csv.DictReader(
    l for l in open("bench/graphs/martin_moyce_front_TZ.csv") if not l.startswith("#"))]

def first_x_reaching(s, y):
    if s[0][1] >= y:
        return s[0][0]
    for a, b in zip(s, s[1:]):
        if a[1] < y <= b[1]:
            return a[0] + (b[0] - a[0]) * (y - a[1]) / (b[1] - a[1])
    return None

def front_error(sim):  # as nodes/metrics/compare_series.rs: error_in x, anchor (1.19, 1.44), min_y 1.44
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

rows = []
for r in [0.02, 0.014, 0.01, 0.007, 0.005, 0.0035]:
    p = subprocess.run([py, "bench/peers/sph_splishsplash.py", str(r), "3.5", "dfsph"],
                       capture_output=True, text=True)
    line = [l for l in p.stdout.splitlines() if l.startswith("{")]
    if p.returncode != 0 or not line:
        rows.append(["SPlisHSPlasH dfsph", r, "failed", "peer", "", "", "", ""])
        print(f"  r = {r}: peer failed: {p.stderr.strip()[-300:]}", file=sys.stderr)
        continue
    d = json.loads(line[-1])
    e = front_error([tuple(x) for x in d["front"]])
    rows.append(["SPlisHSPlasH dfsph", r, "ok" if e is not None else "failed", "", f"{1000 * d['seconds']:.4f}",
                 "" if e is None else e, d["steps"], d["particles"]])
    print(f"  r = {r}: {d['particles']} particles, {d['steps']} steps, {d['seconds']:.2f} s, front error {e}")
with open(out, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["fluid.solver", "fluid.particle_radius", "status", "error_kind", "ms:fluid",
                "front_error.error", "steps", "particles"])
    w.writerows(rows)
PY
"$CGNODES" chart docs/charts/sph_dam_break.csv "$peer_csv" --x ms:fluid --y front_error.error \
  --series fluid.solver --log-x --log-y \
  --title "2-D dam break to T = 3.5: front error vs wall time, with SPlisHSPlasH DFSPH" \
  --plot docs/charts/sph_dam_break.svg
echo "wrote $peer_csv and docs/charts/sph_dam_break.svg"
