#!/usr/bin/env bash
# raster_antialiasing: the sweep varies render.antialiasing (msaa, ssaa) x render.samples;
# with 1 sample both modes are the same renderer without anti-aliasing. This step relabels
# those runs "none", takes the median render time of the repeats of each configuration and
# redraws docs/charts/raster_antialiasing.svg with the three series none / msaa / ssaa.
set -euo pipefail
[ "${1:-}" = --check ] && exit 0  # no peer
CGNODES=${CGNODES:-target/release/cgnodes}
csv=docs/charts/raster_antialiasing.csv
modes=docs/charts/raster_antialiasing_modes.csv
if ! command -v python3 >/dev/null; then
  echo "raster_antialiasing.sh: python3 not found" >&2
  exit 1
fi
python3 - "$csv" "$modes" <<'PY'
import csv, statistics, sys
src, dst = sys.argv[1], sys.argv[2]
groups = {}
for r in csv.DictReader(open(src)):
    s = int(r["render.samples"])
    mode = "none" if s == 1 else r["render.antialiasing"]
    key = (mode, s, r["status"])
    g = groups.setdefault(key, {"ms": [], "rmse": r["cmp.rmse"], "psnr": r["cmp.psnr"], "kind": r["error_kind"]})
    g["ms"].append(float(r["ms:render"]))
with open(dst, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["mode", "samples", "runs", "status", "error_kind", "render_ms", "rmse", "psnr"])
    for (mode, s, status), g in sorted(groups.items(), key=lambda kv: (kv[0][0], kv[0][1])):
        w.writerow([mode, s, len(g["ms"]), status, g["kind"], f"{statistics.median(g['ms']):.3f}", g["rmse"], g["psnr"]])
PY
"$CGNODES" chart "$modes" --x render_ms --y rmse --series mode --log-x --log-y \
  --title "Raster anti-aliasing: RMSE against a 64-sample SSAA reference (camel, 640x480)" \
  --plot docs/charts/raster_antialiasing.svg
echo "wrote $modes and docs/charts/raster_antialiasing.svg"
