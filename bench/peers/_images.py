"""Shared helpers of the peer scripts (the image peers, curves_scipy.py, insects_sklearn.py,
warp_skimage.py, poisson_opencv.py): the peers' virtual environment, the cgnodes binary, and,
for the image peers, a PNG reader and writer with only `zlib`
and `struct` (8-bit grey, RGB or RGBA, non-interlaced), so that no imaging library is needed
to hand both sides the same pixels."""
import os
import struct
import subprocess
import sys
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
VENV = os.path.join(ROOT, "target", "peers-venv")


def ensure(modules, packages, script, flag):
    """Re-executes `script` inside target/peers-venv with `packages` installed when one of
    `modules` cannot be imported."""
    try:
        for m in modules:
            __import__(m)
        return
    except ImportError:
        pass
    if os.environ.get(flag):
        sys.exit(f"{', '.join(packages)} could not be imported after installing them")
    py = os.path.join(VENV, "bin", "python")
    if not os.path.exists(py):
        subprocess.check_call([sys.executable, "-m", "venv", VENV])
    subprocess.check_call([py, "-m", "pip", "install", "--quiet"] + packages)
    env = dict(os.environ, **{flag: "1"})
    os.execve(py, [py, os.path.abspath(script)] + sys.argv[1:], env)


def cgnodes_bin():
    """$CGNODES, else the release binary of $CARGO_TARGET_DIR or target/; exits when missing."""
    if os.environ.get("CGNODES"):
        return os.environ["CGNODES"]
    target = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
    path = os.path.join(target, "release", "cgnodes")
    if not os.path.exists(path):
        sys.exit(f"no cgnodes binary at {path}: build with cargo build --release or set CGNODES")
    return path


def png_read(path):
    import numpy as np

    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    pos, idat = 8, b""
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        pos += 12 + n
        if kind == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and body[12] == 0, "8-bit non-interlaced only"
        elif kind == b"IDAT":
            idat += body
    ch = {0: 1, 2: 3, 4: 2, 6: 4}[ctype]
    raw = zlib.decompress(idat)
    stride = w * ch
    out = np.zeros((h, stride), np.uint8)
    prev = np.zeros(stride, np.int64)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = np.frombuffer(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)], np.uint8).astype(np.int64)
        if f == 0:
            cur = line
        elif f == 2:
            cur = (line + prev) & 255
        else:  # sub, average, Paeth: sequential along the row
            cur = np.zeros(stride, np.int64)
            for x in range(stride):
                a = cur[x - ch] if x >= ch else 0
                b = prev[x]
                c = prev[x - ch] if x >= ch else 0
                if f == 1:
                    p = a
                elif f == 3:
                    p = (a + b) // 2
                else:
                    pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                    p = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                cur[x] = (line[x] + p) & 255
        out[y] = cur
        prev = cur
    return out.reshape(h, w, ch) if ch > 1 else out.reshape(h, w)


def png_write(path, arr):
    import numpy as np

    arr = np.ascontiguousarray(arr.astype(np.uint8))
    h, w = arr.shape[:2]
    ch = 1 if arr.ndim == 2 else arr.shape[2]
    raw = b"".join(b"\x00" + arr[y].tobytes() for y in range(h))

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)

    head = struct.pack(">IIBBBBB", w, h, 8, {1: 0, 3: 2, 4: 6}[ch], 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", head) + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def run_graph(d, nodes):
    """Runs a graph of `nodes` in folder `d` (outputs in d/out), on one thread (`--threads 1`:
    one node at a time, and faer's kernels, which run in the executor's rayon pool, on one
    thread too) or on $CGNODES_THREADS threads; returns the output folder."""
    import json

    g = os.path.join(d, "g.json")
    with open(g, "w") as f:
        json.dump({"format": "cgnodes-graph", "version": 1, "nodes": nodes}, f)
    out = os.path.join(d, "out")
    subprocess.run([cgnodes_bin(), "run", g, "--out", out, "--threads", os.environ.get("CGNODES_THREADS", "1")], check=True, capture_output=True)
    return out


def read_table(path):
    import csv

    with open(path) as f:
        return [{k: float(v) for k, v in r.items() if v != ""} for r in csv.DictReader(f)]


def result(cases, **extra):
    """Prints the line `bench/peers/compare.py` reads from a script's round: `RESULT {json}`
    with one entry per case (case, ours_ms, peer_ms, accuracy) and `extra` (e.g. the peer's
    version). The script's own table stays above it for a person."""
    import json

    print("RESULT " + json.dumps({"cases": cases, **extra}), flush=True)
