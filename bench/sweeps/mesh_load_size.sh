#!/usr/bin/env bash
# mesh_load_size: after the sweep (mesh_load on every shipped OBJ and USDA mesh, ten runs
# each), take the fastest load time per file, add its format and size in bytes, and redraw
# docs/charts/mesh_load_size.svg with one series per format (the sweep's own chart has one
# series per file).
set -euo pipefail
[ "${1:-}" = --check ] && exit 0  # no peer
CGNODES=${CGNODES:-target/release/cgnodes}
csv=docs/charts/mesh_load_size.csv
best=docs/charts/mesh_load_size_best.csv
if ! command -v python3 >/dev/null; then
  echo "mesh_load_size.sh: python3 not found" >&2
  exit 1
fi
python3 - "$csv" "$best" <<'PY'
import csv, os, statistics, sys
src, dst = sys.argv[1], sys.argv[2]
groups = {}
for r in csv.DictReader(open(src)):
    g = groups.setdefault(r["load.path"], {"ms": [], "rows": []})
    g["rows"].append(r)
    if r["status"] == "ok":
        g["ms"].append(float(r["ms:load"]))
with open(dst, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["file", "format", "bytes", "faces", "vertices", "runs", "status", "error_kind",
                "load_ms", "MB_per_s"])
    for path, g in sorted(groups.items(), key=lambda kv: float(kv[1]["rows"][0]["info.table:faces"] or 0)):
        r = g["rows"][0]
        local = os.path.normpath(os.path.join("bench/sweeps", path))
        size = os.path.getsize(local)
        ok = len(g["ms"]) == len(g["rows"])
        ms = min(g["ms"]) if g["ms"] else float("nan")
        w.writerow([os.path.basename(path), os.path.splitext(path)[1][1:].upper(), size,
                    r["info.table:faces"], r["info.table:vertices"], len(g["rows"]),
                    "ok" if ok else "failed", r["error_kind"], f"{ms:.3f}",
                    f"{size / 1e3 / ms:.1f}" if ms == ms and ms > 0 else ""])
PY
"$CGNODES" chart "$best" --x faces --y load_ms --series format --log-x --log-y \
  --title "mesh_load: load time (fastest of 10) against face count, shipped OBJ and USDA meshes" \
  --plot docs/charts/mesh_load_size.svg
echo "wrote $best and docs/charts/mesh_load_size.svg"
