#!/usr/bin/env bash
# param_tutte_weights: after the sweep (tutte on a circle with uniform / cotangent /
# mean-value weights on seven disk meshes, five runs each), take the fastest tutte time (the machine is shared) of
# the repeats of each (weights, mesh) pair, add the mesh's name, and redraw
# docs/charts/param_tutte_weights.svg from the fastest runs (one point per mesh and weighting).
set -euo pipefail
[ "${1:-}" = --check ] && exit 0  # no peer
CGNODES=${CGNODES:-target/release/cgnodes}
csv=docs/charts/param_tutte_weights.csv
best=docs/charts/param_tutte_weights_best.csv
if ! command -v python3 >/dev/null; then
  echo "param_tutte_weights.sh: python3 not found" >&2
  exit 1
fi
python3 - "$csv" "$best" <<'PY'
import csv, os, statistics, sys
src, dst = sys.argv[1], sys.argv[2]
cols = ["metrics.table:angle_distortion_mean", "metrics.table:arap_energy",
        "metrics.table:area_distortion_mean", "metrics.table:flipped"]
groups = {}
for r in csv.DictReader(open(src)):
    key = (r["tutte.weights"], r["load.path"])
    g = groups.setdefault(key, {"ms": [], "rows": []})
    g["rows"].append(r)
    if r["status"] == "ok":
        g["ms"].append(float(r["ms:tutte"]))
with open(dst, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["weights", "mesh", "runs", "status", "error_kind", "tutte_ms"] + cols)
    for (weights, path), g in groups.items():
        r = g["rows"][0]
        ok = len(g["ms"]) == len(g["rows"])
        ms = f"{min(g['ms']):.3f}" if g["ms"] else ""
        w.writerow([weights, os.path.basename(path), len(g["rows"]), "ok" if ok else "failed",
                    r["error_kind"], ms] + [r[c] for c in cols])
PY
"$CGNODES" chart "$best" --x tutte_ms --y metrics.table:angle_distortion_mean --series weights \
  --log-x --log-y \
  --title "Tutte (circle): mean angle distortion vs time, 7 disk meshes of 562-44,416 faces" \
  --plot docs/charts/param_tutte_weights.svg
echo "wrote $best and docs/charts/param_tutte_weights.svg"
