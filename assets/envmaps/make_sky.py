#!/usr/bin/env python3
"""Writes sky.exr: a small procedural equirectangular environment (64 x 32, RGB float32,
uncompressed scanline OpenEXR written by hand, no libraries besides numpy): a blue sky
brightening towards the horizon, a warm sun disc of radiance 200 at 35 degrees elevation
towards -z rotated 60 degrees about +y, and a dim brown ground. Pixel row 0 is straight up
(theta = 0); column u looks along (sin th sin phi, cos th, -sin th cos phi), phi = 2 pi (u - 1/2),
the convention of cgnodes' `light_environment`.

Run: python3 assets/envmaps/make_sky.py (rewrites assets/envmaps/sky.exr byte for byte).
"""
import os
import struct

import numpy as np

W, H = 64, 32


def directions(w=W, h=H):
    """The direction each texel centre looks along (h x w x 3) and its azimuth phi."""
    v = (np.arange(h) + 0.5) / h
    u = (np.arange(w) + 0.5) / w
    th = np.pi * v[:, None] * np.ones((1, w))
    ph = 2 * np.pi * (u[None, :] - 0.5) * np.ones((h, 1))
    d = np.stack([np.sin(th) * np.sin(ph), np.cos(th), -np.sin(th) * np.cos(ph)], -1)
    return d, ph


def sky():
    d, _ = directions()
    up = d[..., 1]
    img = np.zeros((H, W, 3))
    t = np.clip(up, 0, 1)[..., None]
    horizon = np.array([0.9, 0.95, 1.0])
    zenith = np.array([0.15, 0.3, 0.8])
    img[:] = horizon * (1 - t) + zenith * t
    ground = np.array([0.12, 0.09, 0.06])
    img[up < 0] = ground
    el, az = np.radians(35.0), np.radians(60.0)
    sun = np.array([np.cos(el) * np.sin(az), np.sin(el), -np.cos(el) * np.cos(az)])
    cosang = d @ sun
    img[cosang > np.cos(np.radians(6.0))] = np.array([200.0, 180.0, 150.0])
    return img.astype(np.float32)


def attr(name, typ, data):
    return name.encode() + b"\0" + typ.encode() + b"\0" + struct.pack("<i", len(data)) + data


def write_exr(path, img):
    h, w, _ = img.shape
    chans = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for c in "BGR") + b"\0"
    box = struct.pack("<iiii", 0, 0, w - 1, h - 1)
    header = (
        struct.pack("<ii", 20000630, 2)
        + attr("channels", "chlist", chans)
        + attr("compression", "compression", b"\0")
        + attr("dataWindow", "box2i", box)
        + attr("displayWindow", "box2i", box)
        + attr("lineOrder", "lineOrder", b"\0")
        + attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
        + attr("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0))
        + attr("screenWindowWidth", "float", struct.pack("<f", 1.0))
        + b"\0"
    )
    line = 8 + w * 3 * 4
    start = len(header) + 8 * h
    table = b"".join(struct.pack("<Q", start + y * line) for y in range(h))
    body = b""
    for y in range(h):
        data = b"".join(img[y, :, c].astype("<f4").tobytes() for c in (2, 1, 0))
        body += struct.pack("<ii", y, len(data)) + data
    with open(path, "wb") as f:
        f.write(header + table + body)


if __name__ == "__main__":
    write_exr(os.path.join(os.path.dirname(os.path.abspath(__file__)), "sky.exr"), sky())
