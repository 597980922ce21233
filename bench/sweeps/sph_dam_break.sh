#!/usr/bin/env bash
# sph_dam_break: overlays SPlisHSPlasH's DFSPH (PyPI pysplishsplash, bench/peers/sph_splishsplash.py,
# same tank, column, CFL 0.4 and Akinci boundary; viscosity off) on the sweep's chart. For each
# particle radius it runs the peer to T = 3.5, scores its front exactly as the sweep's
# compare_series node does (error in T against bench/graphs/martin_moyce_front_TZ.csv for
# Z >= 1.44, time shifted so that T = 1.19 at Z = 1.44), writes
# docs/charts/sph_dam_break_splishsplash.csv with the sweep's column names and redraws
# docs/charts/sph_dam_break.svg with both CSVs. The Python is $SPH_PEER_PYTHON, else $PEERS_PYTHON
# (bench/run_all sets target/peers-venv's), default python3. pysplishsplash is required:
# without it (`--check` says so) the script fails and draws nothing, so the published chart
# never loses SPlisHSPlasH's series.
set -euo pipefail
py=${SPH_PEER_PYTHON:-${PEERS_PYTHON:-python3}}
peer_csv=docs/charts/sph_dam_break_splishsplash.csv
export LD_PRELOAD=/lib/x86_64-linux-gnu/libGLdispatch.so.0
# SPlisHSPlasH is OpenMP-parallel; with the default spin-waiting its threads lose 4-5x to other
# jobs on a shared machine (measured: 6.8 s against 1.5 s at r = 0.01), so wait passively unless told.
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}
if ! "$py" -c 'import pysplishsplash, numpy' 2>/dev/null; then
  echo "pysplishsplash not importable by $py (bench/run_all --peers installs it into target/peers-venv)" >&2
  exit 1
fi
[ "${1:-}" = --check ] && exit 0
"$py" - "$peer_csv" <<'PY'
import csv, json, subprocess, sys
sys.path.insert(0, "bench/peers")
from sph_front import front_error  # as the sweep's compare_series node scores ours
out = sys.argv[1]
py = sys.executable

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
