#!/usr/bin/env bash
# image_warp_grid: after the grid sweep, the peer comparison of issue 24 in the same run:
# scikit-image's ThinPlateSplineTransform + warp(order=1) against image_warp (rbf,
# thin_plate, inverse) on a 1024x1024 image with 32 control points. The script installs
# scikit-image into target/peers-venv when it is missing; its JSON goes to
# docs/charts/image_warp_skimage.json (figures quoted in docs/image.md).
# scikit-image is required (`--check`): without it the script fails.
set -euo pipefail
py=${PEERS_PYTHON:-python3}
if ! "$py" -c 'import skimage' 2>/dev/null; then
  echo "scikit-image not importable by $py (bench/run_all --peers installs it into target/peers-venv)" >&2
  exit 1
fi
[ "${1:-}" = --check ] && exit 0
CGNODES=${CGNODES:-target/release/cgnodes}
"$py" bench/peers/warp_skimage.py "$CGNODES" 5 > docs/charts/image_warp_skimage.json
cat docs/charts/image_warp_skimage.json
