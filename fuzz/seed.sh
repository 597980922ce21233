#!/usr/bin/env bash
# Builds the seed corpora of the fuzz targets from the project's own files (assets/, tests/data/,
# graphs/, examples/) and a few generated cases. Files over 64 KiB are skipped (fuzzers mutate
# small inputs best). Usage: fuzz/seed.sh  (writes fuzz/corpus/<target>/)
set -euo pipefail
cd "$(dirname "$0")/.."
C=fuzz/corpus
mkdir -p $C/{graph_json,graph_f3d,obj,mtl,off,ply,usda,npy,csv,image,plugin_manifest,plugin_reply}
seed() { # target, files...
  local t=$1; shift
  for f in "$@"; do
    [ -f "$f" ] && [ "$(stat -c %s "$f")" -le 65536 ] && cp "$f" "$C/$t/$(echo "$f" | tr / _)"
  done
  true
}
shopt -s globstar nullglob
seed graph_json graphs/*.json tests/data/bad/*.json
seed graph_f3d tests/data/f3d/*.json
seed obj assets/**/*.obj tests/data/**/*.obj
seed mtl assets/**/*.mtl tests/data/**/*.mtl
seed off assets/**/*.off tests/data/**/*.off
seed ply assets/**/*.ply tests/data/**/*.ply
seed usda assets/**/*.usda tests/data/**/*.usda
seed csv assets/**/*.csv tests/data/**/*.csv
seed image assets/**/*.{png,jpg,jpeg,bmp,gif,hdr,exr} tests/data/**/*.{png,jpg,jpeg,bmp,gif,hdr,exr}
seed plugin_manifest examples/**/cgnodes-plugin.json tests/data/**/cgnodes-plugin.json
# generated seeds: binary PLY, OFF variants, npy arrays, plugin replies
printf 'OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n' > $C/off/quad.off
printf 'ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n' > $C/ply/tri_le.ply
python3 - "$C" <<'PY'
import struct, sys, json
c = sys.argv[1]
with open(f"{c}/ply/tri_le.ply", "ab") as f:
    f.write(struct.pack("<9f", 0,0,0, 1,0,0, 0,1,0) + struct.pack("<B3i", 3, 0, 1, 2))
def npy(shape, descr, payload):
    h = "{'descr': '%s', 'fortran_order': False, 'shape': %s, }" % (descr, repr(tuple(shape)))
    h = h + " " * ((64 - (10 + len(h) + 1) % 64) % 64) + "\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(h)) + h.encode() + payload
arrays = {
    "f64_3x3": npy([3, 3], "<f8", struct.pack("<9d", *range(9))),
    "f32_2x3": npy([2, 3], "<f4", struct.pack("<6f", *range(6))),
    "i32_1x3": npy([1, 3], "<i4", struct.pack("<3i", 0, 1, 2)),
    "i64_4": npy([4], "<i8", struct.pack("<4q", 0, 1, 2, 3)),
}
for k, v in arrays.items():
    open(f"{c}/npy/{k}.npy", "wb").write(v)
replies = {
    "mesh": ({"positions": "a.npy", "faces": [[0, 1, 2]]}, arrays["f64_3x3"]),
    "float": (1.5, b""),
    "list": ([1, 2, 3], b""),
    "points": ({"positions": "a.npy"}, arrays["f32_2x3"]),
    "table": ({"columns": {"x": [1, 2], "y": [3, 4]}}, b""),
}
for k, (j, n) in replies.items():
    open(f"{c}/plugin_reply/{k}", "wb").write(json.dumps(j).encode() + b"\0" + n)
PY
printf 'x,y\n0,1\n1,2\n# comment\n 2 , 3 \n' > $C/csv/xy.csv
# Truncated and corrupted variants of every seed (issue 56): the first half, and one byte
# flipped in the middle; readers must refuse both with an error, never a partial result.
python3 - "$C" <<'PY'
import os, sys
c = sys.argv[1]
for t in os.listdir(c):
    for name in os.listdir(f"{c}/{t}"):
        if name.startswith(("cut_", "flip_")):
            continue
        b = open(f"{c}/{t}/{name}", "rb").read()
        if len(b) < 4:
            continue
        open(f"{c}/{t}/cut_{name}", "wb").write(b[: len(b) // 2])
        f = bytearray(b)
        f[len(f) // 2] ^= 0x10
        open(f"{c}/{t}/flip_{name}", "wb").write(bytes(f))
PY
for t in $C/*; do echo "$(ls "$t" | wc -l) $t"; done
