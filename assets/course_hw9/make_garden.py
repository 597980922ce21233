#!/usr/bin/env python3
"""Writes garden.exr: a small procedural stand-in for the course's hw9 dome light texture
(garden.exr is not in the shared assets). 64 x 32 equirectangular, RGB float32, uncompressed
scanline OpenEXR written by hand with the writer of assets/envmaps/make_sky.py (numpy only):
a pale blue sky brightening towards the horizon, a soft sun of radiance 20 at 50 degrees
elevation, a band of dark green hedge just above the horizon and a green lawn below. Same
convention as cgnodes' `light_environment`: row 0 is straight up (+y), column u looks along
(sin th sin phi, cos th, -sin th cos phi), phi = 2 pi (u - 1/2).

Run: python3 assets/course_hw9/make_garden.py (rewrites garden.exr byte for byte).
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "envmaps"))
from make_sky import directions, write_exr  # noqa: E402

W, H = 64, 32


def garden():
    d, ph = directions(W, H)
    up = d[..., 1]
    t = np.clip(up, 0, 1)[..., None]
    img = np.array([0.95, 0.97, 1.0]) * (1 - t) + np.array([0.35, 0.55, 0.95]) * t
    hedge = (up >= 0) & (up < 0.12 + 0.04 * np.sin(5 * ph))
    img[hedge] = np.array([0.05, 0.18, 0.04])
    img[up < 0] = np.array([0.12, 0.32, 0.08])
    el, az = np.radians(50.0), np.radians(-40.0)
    sun = np.array([np.cos(el) * np.sin(az), np.sin(el), -np.cos(el) * np.cos(az)])
    img[d @ sun > np.cos(np.radians(5.0))] = np.array([20.0, 19.0, 17.0])
    return img.astype(np.float32)


if __name__ == "__main__":
    write_exr(os.path.join(os.path.dirname(os.path.abspath(__file__)), "garden.exr"), garden())
