#!/usr/bin/env bash
# trace_cornell_spp: after the sweep (cgnodes' bsdf / nee / mis at several spp, two runs
# each), keep the faster of the two runs of each configuration (the first run of the
# sweep shares the cores with the 1024-spp reference render), then render mi.cornell_box() with bench/peers/trace_mitsuba.py at the same spp
# (box filter, max_depth 8), score its images against the same reference with the same
# mask, and overlay it: docs/charts/trace_cornell_spp.svg. Mitsuba 3 is required: without it
# (`--check` says so) the script fails and draws nothing, so the published chart never loses
# Mitsuba's series. The peer's Python is $PEERS_PYTHON (bench/run_all sets
# target/peers-venv's), default python3.
set -euo pipefail
py=${PEERS_PYTHON:-python3}
if ! "$py" -c 'import mitsuba' 2>/dev/null; then
  echo "mitsuba not importable by $py (bench/run_all --peers installs it into target/peers-venv)" >&2
  exit 1
fi
[ "${1:-}" = --check ] && exit 0
CGNODES=${CGNODES:-target/release/cgnodes}
csv=docs/charts/trace_cornell_spp.csv
best=docs/charts/trace_cornell_spp_best.csv
peer=docs/charts/trace_cornell_spp_mitsuba.csv
ref=target/trace_cornell_spp/trace_cornell_spp_reference.exr
spp=1,4,16,64
title="Cornell box path tracing: RMSE against a 1024-spp reference (256x256, light masked)"
python3 - "$csv" "$best" <<'PY'
import csv, sys
src, dst = sys.argv[1], sys.argv[2]
best = {}
for r in csv.DictReader(open(src)):
    key = (r["render.strategy"], int(r["render.spp"]))
    b = best.get(key)
    if b is None or (r["status"] == "ok" and (b["status"] != "ok" or float(r["ms:render"]) < float(b["ms:render"]))):
        best[key] = r
cols = ["render.strategy", "render.spp", "status", "error_kind", "ms:render", "cmp.rmse", "cmp.psnr"]
with open(dst, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(cols)
    for key in sorted(best):
        w.writerow([best[key][c] for c in cols])
PY
files=("$best")
mkdir -p target/trace_cornell_spp/mitsuba
"$py" bench/peers/trace_mitsuba.py --spp "$spp" --variants scalar_rgb,llvm_ad_rgb \
  --out target/trace_cornell_spp/mitsuba
"$py" - "$ref" target/trace_cornell_spp/mitsuba "$peer" bench/graphs/trace_cornell_spp_mask.png <<'PY'
import csv, json, os, sys
import numpy as np
import mitsuba as mi
mi.set_variant("scalar_rgb")
ref_path, folder, dst, mask_path = sys.argv[1:5]
load = lambda p: np.array(mi.Bitmap(p).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False), dtype=np.float64)
ref = load(ref_path)
keep = np.array(mi.Bitmap(mask_path), dtype=np.float64).reshape(ref.shape[0], ref.shape[1], -1)[..., 0] > 127
runs = json.load(open(os.path.join(folder, "mitsuba.json")))["runs"]
with open(dst, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["render.strategy", "render.spp", "status", "error_kind", "ms:render", "cmp.rmse", "cmp.psnr", "cpu_ms"])
    for r in runs:
        img = load(os.path.join(folder, r["exr"]))
        rmse = float(np.sqrt(np.mean((img[keep] - ref[keep]) ** 2)))
        w.writerow([f"mitsuba {r['variant']} (mis)", r["spp"], "ok", "", f"{1e3 * r['seconds']:.3f}",
                    rmse, 20 * np.log10(1 / rmse), f"{1e3 * r['cpu_seconds']:.3f}"])
        print(f"mitsuba {r['variant']} {r['spp']:4d} spp: {1e3 * r['seconds']:8.1f} ms, RMSE {rmse:.5f}")
PY
files+=("$peer")
"$CGNODES" chart "${files[@]}" --x ms:render --y cmp.rmse --series render.strategy --log-x --log-y \
  --title "$title" --plot docs/charts/trace_cornell_spp.svg
echo "wrote $best${files[1]:+ and $peer} and docs/charts/trace_cornell_spp.svg"
