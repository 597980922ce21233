"""SPlisHSPlasH (PyPI `pysplishsplash`) on the 2-D Martin & Moyce dam break, for bench/sph.rs.

Usage: LD_PRELOAD=/lib/x86_64-linux-gnu/libGLdispatch.so.0 python sph_splishsplash.py RADIUS T_END [dfsph|wcsph]
Prints one JSON line: particles, steps, seconds (simulation only), front history [[T, Z], ...].
Geometry as bench/sph.rs: column a x 2a (a = 0.5 m) against the left wall of a 4a x 2.5a tank,
g = 9.81, Akinci boundary particles, viscosity off, CFL time step. Front = 5th-largest particle x
plus the particle radius.
"""
import json
import os
import sys
import tempfile
import time

import numpy as np
import pysplishsplash as sph

r = float(sys.argv[1])
t_end = float(sys.argv[2])
method = sys.argv[3] if len(sys.argv) > 3 else "dfsph"
a, g = 0.5, 9.81
tmp = tempfile.mkdtemp(prefix="sph_peer_")
# A unit box; the tank is this box scaled, with inward normals (isWall + mapInvert).
box = os.path.join(tmp, "UnitBox.obj")
with open(box, "w") as f:
    v = [(x, y, z) for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]
    f.write("".join(f"v {x} {y} {z}\n" for x, y, z in v))
    quads = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]
    for q in quads:
        f.write(f"f {q[0]} {q[1]} {q[2]}\nf {q[0]} {q[2]} {q[3]}\n")
scene = {
    "Configuration": {
        "particleRadius": r,
        "sim2D": True,
        "density0": 1000,
        "simulationMethod": 4 if method == "dfsph" else 0,
        "gravitation": [0, -g, 0],
        "cflMethod": 1,
        "cflFactor": 0.4,
        "cflMaxTimeStepSize": 0.005,
        "maxIterations": 100,
        "maxError": 0.1,
        "maxIterationsV": 100,
        "maxErrorV": 0.1,
        "enableDivergenceSolver": True,
        "boundaryHandlingMethod": 0,
        "stiffness": 1000.0 * 100.0 * 2.0 * g * 2.0 * a / 7.0 / 1000.0,
        "exponent": 7,
        "stopAt": -1,
        "enableVTKExport": False,
        "enablePartioExport": False,
    },
    "Materials": [{"id": "Fluid", "viscosity": 0.0, "viscosityMethod": 0, "colorMapType": 1}],
    "RigidBodies": [{
        "geometryFile": box,
        "translation": [2 * a, 1.25 * a, 0],
        "scale": [4 * a, 2.5 * a, 1],
        "color": [0.1, 0.4, 0.6, 1.0],
        "isDynamic": False,
        "isWall": True,
        "mapInvert": True,
        "mapThickness": 0.0,
        "mapResolution": [40, 30, 1],
    }],
    "FluidBlocks": [{"denseMode": 0, "start": [0.0, 0.0, -0.5], "end": [a, 2 * a, 0.5],
                     "translation": [0, 0, 0], "scale": [1, 1, 1]}],
}
scene_file = os.path.join(tmp, "dam.json")
with open(scene_file, "w") as f:
    json.dump(scene, f)

base = sph.Exec.SimulatorBase()
base.init(useGui=False, outputDir=tmp, sceneFile=scene_file)
base.initSimulation()
sim = sph.Simulation.getCurrent()
fluid = sim.getFluidModel(0)
tm = sph.TimeManager.getCurrent()
n = fluid.numActiveParticles()


def front():
    xs = np.array([fluid.getPosition(i)[0] for i in range(n)])
    return float(np.sort(xs)[-5]) + r


x0 = front()
ys = np.array([fluid.getPosition(i)[1] for i in range(n)])
height = float(ys.max()) + r
nn = (height / x0) ** 0.5
ts = nn * (g / x0) ** 0.5
hist = [(0.0, 1.0)]
state = {"steps": 0, "next": 0.005, "probe": 0.0}


def on_step():
    state["steps"] += 1
    t = tm.getTime()
    if t >= state["next"]:
        t0 = time.perf_counter()
        hist.append((t * ts, front() / x0))
        state["next"] += 0.005
        state["probe"] += time.perf_counter() - t0


base.setTimeStepCB(on_step)
base.setValueFloat(base.STOP_AT, t_end / ts)
t0 = time.perf_counter()
base.runSimulation()
sim_seconds = time.perf_counter() - t0 - state["probe"]
print(json.dumps({"particles": n, "steps": state["steps"], "seconds": sim_seconds, "front": hist}))
base.cleanup()
