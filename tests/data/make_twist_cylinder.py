"""Writes twist_cylinder.usda: a closed cylinder (radius 0.5, length 4 along z, capped) bound
to two joints, the second's weight rising linearly from 0 at z = 0 to 1 at z = 4, and an
animation twisting the second joint about z by `time` degrees (samples at 0 and 180: USD's
slerp between the identity and the half turn is a rotation by exactly time/180 of it). The
candy-wrapper test of DQS against LBS (tests/it/anim.rs, bench/sweeps/skin_twist.json).
`python3 tests/data/make_twist_cylinder.py > tests/data/twist_cylinder.usda`."""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _skinned_tube import tube_mesh  # noqa: E402

RINGS, SEG, R, L = 25, 24, 0.5, 4.0
pts, idx, wts = [], [], []


def bind(z):
    w = min(max(z / L, 0.0), 1.0)
    idx.extend([0, 1])
    wts.extend([1.0 - w, w])


for r in range(RINGS):
    z = L * r / (RINGS - 1)
    for s in range(SEG):
        a = 2 * math.pi * s / SEG
        pts.append((R * math.cos(a), R * math.sin(a), z))
        bind(z)
bottom, top = len(pts), len(pts) + 1
pts += [(0.0, 0.0, 0.0), (0.0, 0.0, L)]
bind(0.0)
bind(L)
counts, faces = [], []
for r in range(RINGS - 1):
    for s in range(SEG):
        a, b = r * SEG + s, r * SEG + (s + 1) % SEG
        counts.append(4)
        faces += [a, b, b + SEG, a + SEG]
last = (RINGS - 1) * SEG
for s in range(SEG):
    counts += [3, 3]
    faces += [bottom, (s + 1) % SEG, s]
    faces += [top, last + s, last + (s + 1) % SEG]
out = []
w = out.append
w('#usda 1.0\n(\n    defaultPrim = "Model"\n    startTimeCode = 0\n    endTimeCode = 180\n    upAxis = "Z"\n)\n')
w('def SkelRoot "Model"\n{\n')
w('    def Skeleton "Skel" (\n        prepend apiSchemas = ["SkelBindingAPI"]\n    )\n    {\n')
w('        uniform token[] joints = ["A", "A/B"]\n')
w("        uniform matrix4d[] bindTransforms = [((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1)), ((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 2, 1))]\n")
w("        uniform matrix4d[] restTransforms = [((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1)), ((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 2, 1))]\n")
w("        rel skel:animationSource = </Model/Skel/Twist>\n\n")
w('        def SkelAnimation "Twist"\n        {\n')
w('            uniform token[] joints = ["A/B"]\n')
w("            float3[] translations = [(0, 0, 2)]\n")
w("            quatf[] rotations.timeSamples = {\n                0: [(1, 0, 0, 0)],\n                180: [(0, 0, 0, 1)],\n            }\n")
w("        }\n    }\n\n")
tube_mesh(w, counts, faces, ", ".join("(%.9g, %.9g, %.9g)" % p for p in pts), idx, wts, 2)
print("".join(out), end="")
