"""Writes skin_cylinder.usda: a tessellated cylinder bound to a four-joint chain, four
influences per vertex (indices in shuffled order), animated rotations (time samples 1, 4, 10),
a constant scale on one joint and a geometry bind transform. The test asset for comparing
`skin` with usd-core's UsdSkel (tests/it/anim.rs). Plain Python, no USD library needed:
`python3 tests/data/make_skin_cylinder.py > tests/data/skin_cylinder.usda`."""
import math
import os
import random
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _skinned_tube import tube_mesh  # noqa: E402

random.seed(7)
RINGS, SEG, R, L = 9, 12, 0.5, 6.0
joints = ["Root", "Root/J1", "Root/J1/J2", "Root/J1/J2/J3"]
jz = [0.0, 2.0, 4.0, 6.0]
pts, idx, wts = [], [], []
for r in range(RINGS):
    z = L * r / (RINGS - 1)
    for s in range(SEG):
        a = 2 * math.pi * s / SEG
        pts.append((R * math.cos(a), R * math.sin(a), z))
        raw = [math.exp(-((z - j) / 1.3) ** 2) for j in jz]
        tot = sum(raw)
        pairs = [(j, w / tot) for j, w in enumerate(raw)]
        random.shuffle(pairs)
        idx += [p[0] for p in pairs]
        wts += [p[1] for p in pairs]
counts, faces = [], []
for r in range(RINGS - 1):
    for s in range(SEG):
        a, b = r * SEG + s, r * SEG + (s + 1) % SEG
        counts.append(4)
        faces += [a, b, b + SEG, a + SEG]


def q(axis, deg):
    h = math.radians(deg) / 2
    n = math.sqrt(sum(x * x for x in axis))
    return (math.cos(h),) + tuple(math.sin(h) * x / n for x in axis)


def mat(t):
    return "((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (%r, %r, %r, 1))" % t


def qs(v):
    return "(%r, %r, %r, %r)" % v


samples = {
    1: [q((1, 0, 0), 0), q((1, 0, 0), 0), q((0, 1, 0), 0), q((1, 1, 0), 0)],
    4: [q((0, 0, 1), 30), q((1, 0, 0), 50), q((0, 1, 0), -40), q((1, 1, 0), 70)],
    10: [q((0, 0, 1), -20), q((1, 0.2, 0), 110), q((0.3, 1, 0), 85), q((1, 1, 0.5), -60)],
}
out = []
w = out.append
w('#usda 1.0\n(\n    defaultPrim = "Model"\n    startTimeCode = 1\n    endTimeCode = 10\n    upAxis = "Z"\n)\n')
w('def SkelRoot "Model" (\n    prepend apiSchemas = ["SkelBindingAPI"]\n)\n{\n')
w('    def Skeleton "Skel" (\n        prepend apiSchemas = ["SkelBindingAPI"]\n    )\n    {\n')
w("        uniform token[] joints = [%s]\n" % ", ".join('"%s"' % j for j in joints))
w("        uniform matrix4d[] bindTransforms = [%s]\n" % ", ".join(mat((0.0, 0.0, z)) for z in jz))
w("        uniform matrix4d[] restTransforms = [%s]\n" % ", ".join(mat((0.0, 0.0, z if i == 0 else 2.0)) for i, z in enumerate(jz)))
w("        rel skel:animationSource = </Model/Skel/Anim>\n\n")
w('        def SkelAnimation "Anim"\n        {\n')
w("            uniform token[] joints = [%s]\n" % ", ".join('"%s"' % j for j in joints))
w("            float3[] translations = [(0, 0, 0), (0, 0, 2), (0, 0, 2), (0, 0, 2)]\n")
w("            quatf[] rotations.timeSamples = {\n")
for t, v in samples.items():
    w("                %d: [%s],\n" % (t, ", ".join(qs(x) for x in v)))
w("            }\n")
w("            half3[] scales = [(1, 1, 1), (1, 1, 1), (1.25, 1, 1), (1, 1, 1)]\n")
w("        }\n    }\n\n")
tube_mesh(w, counts, faces, ", ".join("(%r, %r, %r)" % p for p in pts), idx, wts, 4,
          "((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0.05, -0.1, 0.2, 1))")
print("".join(out), end="")
