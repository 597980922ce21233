#!/usr/bin/env bash
# runtime_cache: the sweep runs, for each grid size n, the graph cold (save.path =
# first_run.csv: every node computes) and then with only the writer's path changed
# (rerun.csv: grid, mesh_info, tutte and uv_metrics come from the executor's cache). This step
# redraws docs/charts/runtime_cache.svg as wall time against vertex count, with a third series
# "executor only": the rerun's total minus the writer's own time (cache lookups, scheduling).
set -euo pipefail
[ "${1:-}" = --check ] && exit 0  # no peer
csv=docs/charts/runtime_cache.csv
out=docs/charts/runtime_cache_runs.csv
if ! command -v python3 >/dev/null; then
  echo "runtime_cache.sh: python3 not found" >&2
  exit 1
fi
python3 - "$csv" "$out" <<'PY'
import csv, sys
src, dst = sys.argv[1], sys.argv[2]
rows = []
for r in csv.DictReader(open(src)):
    v = r["info.table:vertices"]
    if r["save.path"] == "first_run.csv":
        rows.append(["cold run", r["n.value"], v, r["status"], r["total_ms"]])
    else:
        rows.append(["rerun: only the writer runs", r["n.value"], v, r["status"], r["total_ms"]])
        rows.append(["rerun minus the writer: executor only", r["n.value"], v, r["status"],
                     f"{float(r['total_ms']) - float(r['ms:save']):.4f}"])
with open(dst, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["run", "n", "vertices", "status", "ms"])
    w.writerows(rows)
PY
"$CGNODES" chart "$out" --x vertices --y ms --series run --log-x --log-y \
  --title "Executor cache: wall time of a run against mesh size (Tutte on an n x n grid)" \
  --plot docs/charts/runtime_cache.svg
echo "wrote $out and docs/charts/runtime_cache.svg"
