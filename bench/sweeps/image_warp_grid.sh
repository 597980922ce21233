#!/usr/bin/env bash
# image_warp_grid: after the grid sweep, the peer comparison of issue 24 in the same run:
# scikit-image's ThinPlateSplineTransform + warp(order=1) against image_warp (rbf,
# thin_plate, inverse) on a 1024x1024 image with 32 control points. The script installs
# scikit-image into target/peers-venv when it is missing; its JSON goes to
# docs/charts/image_warp_skimage.json (figures quoted in docs/image.md).
set -euo pipefail
CGNODES=${CGNODES:-target/release/cgnodes}
if ! command -v python3 >/dev/null; then
  echo "image_warp_grid.sh: python3 not found; skipping the scikit-image comparison"
  exit 0
fi
python3 bench/peers/warp_skimage.py "$CGNODES" 5 > docs/charts/image_warp_skimage.json
cat docs/charts/image_warp_skimage.json
