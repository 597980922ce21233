#!/usr/bin/env bash
# arap_iterations: after the sweep (cgnodes' arap on camelhead, injective true / false,
# 0-100 iterations, tolerance 0, five runs each), take the fastest run of each
# configuration (the machine is shared) and label the series "cgnodes fold-free" / "cgnodes plain". Then
# run bench/peers/arap_libigl.py on the same mesh
# (start: igl.harmonic, then igl.arap_solve one iteration at a time) and write its points at
# the same iteration counts with the same columns: ms:arap = harmonic + precomputation +
# cumulative solve time (ours: Tutte mean-value start + setup + iterations), arap.log:energy
# = the unscaled ARAP energy sum A((s1-1)^2+(s2-1)^2)/sum A, metrics.table:* = after scaling
# the UV area to the 3-D area. Redraws docs/charts/arap_iterations.svg (energy) and draws
# docs/charts/arap_iterations_flips.svg (flipped triangles) with all series.
# libigl is required: without it (`--check` says so) the script fails and draws nothing, so
# the published chart never loses libigl's series. The peer's Python is $PEERS_PYTHON
# (bench/run_all sets target/peers-venv's), default python3.
set -euo pipefail
py=${PEERS_PYTHON:-python3}
if ! "$py" -c 'import igl' 2>/dev/null; then
  echo "libigl not importable by $py (bench/run_all --peers installs it into target/peers-venv)" >&2
  exit 1
fi
[ "${1:-}" = --check ] && exit 0
CGNODES=${CGNODES:-target/release/cgnodes}
csv=docs/charts/arap_iterations.csv
best=docs/charts/arap_iterations_best.csv
peer=docs/charts/arap_iterations_libigl.csv
mesh=assets/meshes/camelhead.obj
iters=0,1,2,5,10,20,50,100
python3 - "$csv" "$best" <<'PY'
import csv, statistics, sys
src, dst = sys.argv[1], sys.argv[2]
cols = ["arap.log:energy", "metrics.table:arap_energy", "metrics.table:flipped", "arap.log:blocked:sum",
        "arap.log:iteration", "metrics.table:collapsed", "metrics.table:angle_distortion_max"]
groups = {}
for r in csv.DictReader(open(src)):
    method = "cgnodes fold-free" if r["arap.injective"] == "true" else "cgnodes plain"
    key = (method, int(r["arap.iterations"]), r["status"])
    g = groups.setdefault(key, {"ms": [], "kind": r["error_kind"], "m": [r[c] for c in cols]})
    g["ms"].append(float(r["ms:arap"]))
with open(dst, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["method", "arap.iterations", "runs", "status", "error_kind", "ms:arap"] + cols)
    for (method, it, status), g in sorted(groups.items()):
        w.writerow([method, it, len(g["ms"]), status, g["kind"], f"{min(g['ms']):.3f}"] + g["m"])
PY
files=("$best")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$py" bench/peers/arap_libigl.py "$mesh" 100 "$tmp/igl"
python3 - "$tmp/igl.json" "$peer" "$iters" <<'PY'
import csv, json, sys
src, dst, iters = sys.argv[1], sys.argv[2], {int(i) for i in sys.argv[3].split(",")}
d = json.load(open(src))
setup = d["harmonic_ms"] + d["precompute_ms"]
with open(dst, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["method", "arap.iterations", "runs", "status", "error_kind", "ms:arap",
                "arap.log:energy", "metrics.table:arap_energy", "metrics.table:flipped"])
    for r in d["log"]:
        if r["iteration"] in iters:
            w.writerow(["libigl 2.6 (plain, from harmonic)", r["iteration"], 1, "ok", "",
                        f"{setup + r['elapsed_ms']:.3f}", r["energy_raw"], r["energy"], r["flips"]])
print(f"libigl: {d['faces']} faces, harmonic {d['harmonic_ms']:.1f} ms, precomputation "
      f"{d['precompute_ms']:.1f} ms, {d['iteration_ms']:.2f} ms / iteration")
PY
files+=("$peer")
"$CGNODES" chart "${files[@]}" --x ms:arap --y arap.log:energy --series method --log-x \
  --title "ARAP on camelhead (22,704 faces): energy against time, 0-100 iterations (fastest of 5)" \
  --plot docs/charts/arap_iterations.svg
"$CGNODES" chart "${files[@]}" --x ms:arap --y metrics.table:flipped --series method --log-x \
  --title "ARAP on camelhead: flipped triangles against time, 0-100 iterations" \
  --plot docs/charts/arap_iterations_flips.svg
echo "wrote $best${files[1]:+, $peer}, docs/charts/arap_iterations.svg and docs/charts/arap_iterations_flips.svg"
