#!/usr/bin/env python3
"""Every comparison of cgnodes against a peer library, rerun by one command
(`bench/run_all --peers`, which calls this script):

    python3 bench/peers/compare.py [--smoke] [--only NAME[,NAME...]] [--rounds N]
                                   [--skip-missing] [--list] [--out DIR]

It installs the peers into a virtual environment (target/peers-venv, or $PEERS_VENV) with pip
and re-runs itself there. Then, for each comparison, it alternates cgnodes and the peer over
ROUNDS rounds in this one process tree (round i runs ours, then the peer, on the same input),
and writes one record per comparison through bench/_record.py: bench/results/NAME.json with
the machine, commit, date, threads, each round's milliseconds per case, their medians, the
ratio ours / peer of the medians, and the accuracy of both sides. `--smoke` runs each
comparison at a small size for one round and writes its records to target/peers-smoke/
instead (so CI keeps the scripts alive without touching the published records).

A peer that cannot be installed or imported, or a comparison that fails, is named and makes
the exit status 1; with `--skip-missing` its record is written with status "not measured"
and the reason instead (docs/benchmarks.md then says so).

The comparisons reuse the scripts beside this one: scripts that already run both sides
print a `RESULT {json}` line per round (`_images.result`) or one JSON object; the others are
driven from here with cgnodes' own `--profile-json` node times.
"""
import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import traceback

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.dirname(HERE))
import _record  # noqa: E402

TARGET = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
VENV = os.environ.get("PEERS_VENV", os.path.join(ROOT, "target", "peers-venv"))
# Every peer, as pip installs it. Versions float: each record names the versions it ran.
PACKAGES = ["numpy", "scipy", "libigl", "mitsuba", "opencv-python-headless", "pysplishsplash",
            "warp-lang", "seam-carving", "scikit-image", "scikit-learn", "usd-core"]


class Missing(Exception):
    """The peer (or a tool the comparison needs) is not there."""


class Failed(Exception):
    """The comparison ran and failed."""


# ----------------------------------------------------------------------------- set-up

def in_venv():
    return os.path.realpath(sys.prefix) == os.path.realpath(VENV)


def install_and_reexec():
    """Creates the venv, pip-installs PACKAGES (a no-op when present) and re-executes this
    script with the venv's Python. A package pip cannot install is reported by the
    comparisons that import it (each names its peer)."""
    py = os.path.join(VENV, "bin", "python")
    if not os.path.exists(py):
        subprocess.check_call([sys.executable, "-m", "venv", VENV])
    pip = [py, "-m", "pip", "install", "--quiet", "--disable-pip-version-check"]
    if subprocess.run(pip + PACKAGES).returncode != 0:
        # one package failing must not keep the others out: install them one by one
        for p in PACKAGES:
            if subprocess.run(pip + [p]).returncode != 0:
                print(f"compare.py: pip could not install {p}", file=sys.stderr)
    os.execve(py, [py, os.path.abspath(__file__)] + sys.argv[1:],
              dict(os.environ, PEERS_IN_VENV="1"))


def ensure_llvm():
    """Mitsuba's llvm_ad_rgb needs LLVM 16 or later (Debian bookworm's default 15 aborts):
    installs Debian's libllvm19 with apt-get when it is missing and we are root."""
    import glob
    if glob.glob("/usr/lib/*/libLLVM.so.19*") + glob.glob("/usr/lib/*/libLLVM-19.so"):
        return
    if os.geteuid() == 0 and shutil.which("apt-get"):
        r = subprocess.run("apt-get install -y -qq libllvm19 >/dev/null 2>&1 || "
                           "(apt-get update -qq && apt-get install -y -qq libllvm19)",
                           shell=True, capture_output=True, text=True)
        if r.returncode == 0:
            return
    raise Missing("libllvm19 (Debian) is not installed: apt-get install libllvm19")


def need(*modules, env=None):
    """Checks that the peer's modules import, in a child process (a native library that
    crashes on import must not take this process down); raises Missing naming the first
    that fails."""
    for m in modules:
        r = subprocess.run([sys.executable, "-c", f"import {m}"], capture_output=True, text=True, env=env)
        if r.returncode != 0:
            err = (r.stderr.strip().splitlines() or [f"exit status {r.returncode}"])[-1]
            raise Missing(f"python module {m} cannot be imported ({err})")


def cgnodes_bin():
    path = os.environ.get("CGNODES") or os.path.join(TARGET, "release", "cgnodes")
    if not os.path.exists(path):
        raise Missing(f"no cgnodes binary at {path}: cargo build --release")
    return path


def run(cmd, env=None, cwd=None, what=None, both=False):
    """Runs a command and returns its stdout (`both`: stdout and stderr); raises Failed with
    the end of its stderr when it fails."""
    r = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=cwd)
    if r.returncode != 0:
        tail = "\n".join((r.stderr or r.stdout).strip().splitlines()[-12:])
        raise Failed(f"{what or os.path.basename(str(cmd[1] if len(cmd) > 1 else cmd[0]))} "
                     f"exited {r.returncode}:\n{tail}")
    return r.stdout + r.stderr if both else r.stdout


def timed(cmd, env=None, cwd=None):
    t = time.perf_counter()
    run(cmd, env=env, cwd=cwd)
    return (time.perf_counter() - t) * 1e3


def script_env(ctx, runs=1):
    env = dict(os.environ, CGNODES=ctx.bin, PEERS_RUNS=str(runs))
    env["PATH"] = os.path.join(VENV, "bin") + os.pathsep + env.get("PATH", "")
    if ctx.smoke:
        env["PEERS_SMOKE"] = "1"
    else:
        env.pop("PEERS_SMOKE", None)
    return env


# BLAS held to one thread, for the comparisons where cgnodes runs on one (--threads 1):
# like for like, and OpenBLAS's spinning threads lose several times over to other jobs on a
# shared 2-core machine.
ONE_THREAD = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def script_round(ctx, script, *args, runs=1, env=None):
    """One round of a script that runs both sides: its RESULT line, else its JSON object."""
    out = run([sys.executable, os.path.join(HERE, script), *map(str, args)],
              env={**script_env(ctx, runs), **(env or {})}, what=script)
    for line in out.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    start = out.find("\n{") + 1 if not out.startswith("{") else 0
    try:
        return json.loads(out[start:])
    except ValueError:
        raise Failed(f"{script} printed no RESULT line and no JSON object:\n{out[-600:]}")


def profile_ms(path, node):
    """A node's wall time (ms) in a `cgnodes run --profile-json` file, summed over frames."""
    frames = json.load(open(path))
    return sum(n["ms"] for f in frames for n in f["nodes"] if n["id"] == node)


class Cases:
    """Per case: each round's ours and peer milliseconds, and the last accuracy seen."""

    def __init__(self):
        self.rows = {}

    def add(self, case, ours_ms, peer_ms, accuracy=None, **extra):
        r = self.rows.setdefault(case, {"case": case, "ours_ms": [], "peer_ms": [], "accuracy": {}})
        if ours_ms is not None:
            r["ours_ms"].append(float(ours_ms))
        if peer_ms is not None:
            r["peer_ms"].append(float(peer_ms))
        r["accuracy"].update(accuracy or {})
        r.update(extra)

    def done(self):
        out = []
        for r in self.rows.values():
            if r["ours_ms"] and r["peer_ms"]:
                mo, mp = statistics.median(r["ours_ms"]), statistics.median(r["peer_ms"])
                r.update(median_ours_ms=mo, median_peer_ms=mp, ratio=mo / mp if mp > 0 else None)
                if len(r["ours_ms"]) == len(r["peer_ms"]):
                    r["round_ratios"] = [o / p for o, p in zip(r["ours_ms"], r["peer_ms"]) if p > 0]
            else:
                r.update(median_ours_ms=None, median_peer_ms=None, ratio=None)
            out.append(r)
        return out


def pkg_version(name):
    try:
        from importlib.metadata import version
        return f"{name} {version(name)}"
    except Exception:  # noqa: BLE001
        return name


# ----------------------------------------------------------------------------- comparisons

def uv_similarity_error(ours, peer):
    """Largest distance between two UV layouts of the same vertices after the best
    similarity transform taking ours onto the peer's (least squares over complex numbers:
    z_peer ~ a z_ours + b), relative to the diameter of the peer's layout."""
    import numpy as np
    zp = peer[:, 0] + 1j * peer[:, 1]
    best = None
    for zo in (ours[:, 0] + 1j * ours[:, 1], ours[:, 0] - 1j * ours[:, 1]):  # the two may be mirror images
        a_mat = np.c_[zo, np.ones_like(zo)]
        coef, *_ = np.linalg.lstsq(a_mat, zp, rcond=None)
        err = np.abs(a_mat @ coef - zp).max()
        best = err if best is None else min(best, err)
    return float(best / (np.abs(zp - zp.mean()).max() * 2))


def c_tutte_libigl(ctx):
    """Tutte (cotangent weights, circle boundary) as a user runs it: `cgnodes run` of
    mesh_load -> tutte -> mesh_save with its run report, against a Python process that
    imports libigl and does the same (bench/tutte_whole_run.py's graph and script), whole
    processes timed; and within the same runs the solve alone: the `tutte` node's wall time
    (--profile-json: connectivity, boundary, weights, factorization, solve) against libigl's
    boundary_loop + map_vertices_to_circle + harmonic. Accuracy: the largest UV difference
    after the best similarity transform, relative to the layout's diameter."""
    need("igl", "numpy")
    import numpy as np
    import tutte_whole_run as tw
    meshes = ["camel_b"] if ctx.smoke else ["camel_b", "camelhead", "nefertiti_front", "igea_front"]
    cases = Cases()
    script = os.path.join(ctx.tmp, "tutte_libigl.py")
    # tutte_whole_run.py's script, with the solve timed inside it (printed last)
    timed_script = tw.LIBIGL.replace("bnd = igl.boundary_loop(F)", "import time\nt0 = time.perf_counter()\n"
                                     "bnd = igl.boundary_loop(F)")
    timed_script = timed_script.replace("igl.writeOBJ(", "print((time.perf_counter() - t0) * 1e3)\nigl.writeOBJ(")
    assert timed_script.count("perf_counter") == 2, "tutte_whole_run.LIBIGL changed"
    open(script, "w").write(timed_script)
    for name in meshes:
        mesh = os.path.join(ROOT, "assets/meshes", name + ".obj")
        g = os.path.join(ctx.tmp, name + ".json")
        json.dump(tw.graph(mesh), open(g, "w"))
        out = os.path.join(ctx.tmp, "tutte_out")
        prof = os.path.join(ctx.tmp, "tutte_profile.json")
        ours_cmd = [ctx.bin, "run", g, "--out", out, "-q", "--profile-json", prof]
        igl_obj = os.path.join(ctx.tmp, "igl.obj")
        peer_cmd = [sys.executable, script, mesh, igl_obj]
        timed(ours_cmd), timed(peer_cmd)  # page cache warm
        for _ in range(ctx.rounds):
            t = time.perf_counter()
            run(ours_cmd)
            ours_ms = (time.perf_counter() - t) * 1e3
            t = time.perf_counter()
            solve_peer = float(run(peer_cmd).split()[-1])
            peer_ms = (time.perf_counter() - t) * 1e3
            cases.add(f"{name}, whole process", ours_ms, peer_ms)
            cases.add(f"{name}, solve only", profile_ms(prof, "tutte"), solve_peer)
        from scipy.spatial import cKDTree
        rows = lambda path, tag, k: np.array([[float(x) for x in ln.split()[1:1 + k]]  # noqa: E731
                                              for ln in open(path) if ln.startswith(tag + " ")])
        flat = os.path.join(out, "flat.obj")
        vt, v_ours, v_in = rows(flat, "vt", 2), rows(flat, "v", 3), rows(mesh, "v", 3)
        vp = rows(igl_obj, "v", 2)
        faces = sum(1 for ln in open(mesh) if ln.startswith("f "))
        acc = {"faces": faces}
        faces_of = lambda path: np.array([[int(c.split("/")[0]) - 1 for c in ln.split()[1:4]]  # noqa: E731
                                          for ln in open(path) if ln.startswith("f ")])
        f_ours, f_in = faces_of(flat), faces_of(mesh)
        if len(vt) == len(v_ours) == len(vp) == len(v_in) and f_ours.shape == f_in.shape:
            # mesh_load renumbers the vertices (first use in the faces) and keeps the faces'
            # order, so corresponding corners name corresponding vertices
            idx = np.zeros(len(v_in), np.int64)
            idx[f_in.ravel()] = f_ours.ravel()
            if np.abs(v_ours[idx] - v_in).max() > 1e-4 * np.abs(v_in).max():
                _, idx = cKDTree(v_ours).query(v_in)  # fall back on positions
            acc["uv_max_diff_after_similarity_rel"] = uv_similarity_error(vt[idx], vp)
        cases.add(f"{name}, whole process", None, None, acc)
        cases.add(f"{name}, solve only", None, None, acc)
    return cases.done(), {"peer": pkg_version("libigl"), "threads": "cgnodes: all cores; libigl: its own",
                          "ours": "cgnodes run (whole process, report included)",
                          "peer_side": "python3 + libigl (whole process: import, read, solve, write)"}


def c_arap_libigl(ctx):
    """ARAP parameterization, a fixed number of iterations (tolerance 0; ours stops early
    only when no decrease is left): cgnodes' `arap` node, plain and fold-free (Tutte
    mean-value start, setup, iterations; its wall time from --profile-json, through
    graphs/arap_camelhead.json with the mesh set) against libigl's igl.harmonic start,
    arap_precomputation and arap_solve one iteration at a time, one pinned vertex
    (bench/peers/arap_libigl.py: harmonic + precomputation + iterations). Accuracy: the ARAP
    energy each reaches as minimized, sum A((s1-1)^2+(s2-1)^2)/sum A, and the flipped
    triangles (uv_metrics for ours, the same definition in the script for libigl's)."""
    return _arap(ctx, 5 if ctx.smoke else 100,
                 ["camelhead"] if ctx.smoke else ["camel_b", "camelhead", "nefertiti_front", "igea_front"])


def c_arap_hard_libigl(ctx):
    """As arap_libigl on the hard inputs of the fold-free benchmark, 20 iterations:
    bunny_base (the closed bunny cut open at its base, whose Tutte start is crushed in the
    middle), bunny_open (also cut at both ear tips) and beetle_11holes (eleven holes), shipped
    in assets/meshes/; and three large ones that bench/peers/arap_meshes.py generates at bench
    time: bunny_base4 and bunny_base16 (bunny_base after one and two 1-to-4 midpoint
    subdivisions, 20k and 81k faces, where libigl folds thousands of triangles) and
    nefertiti_open4 (nefertiti_front with two holes, subdivided once, 175k faces)."""
    if ctx.smoke:
        return _arap(ctx, 5, ["bunny_open"])
    gen = os.path.join(ctx.tmp, "meshes")
    run([sys.executable, os.path.join(HERE, "arap_meshes.py"), gen], what="arap_meshes.py")
    large = [os.path.join(gen, n + ".obj") for n in ("bunny_base4", "bunny_base16", "nefertiti_open4")]
    return _arap(ctx, 20, ["bunny_base", "bunny_open", "beetle_11holes"] + large)


def _arap(ctx, iters, meshes):
    need("igl", "numpy")
    import csv
    graph = os.path.join(ROOT, "graphs/arap_camelhead.json")
    cases = Cases()
    for mesh in meshes:
        # a name is a shipped mesh (assets/meshes/NAME.obj), a path one made for the run
        if not mesh.endswith(".obj"):
            mesh = os.path.join(ROOT, "assets/meshes", mesh + ".obj")
        name = os.path.basename(mesh)[:-len(".obj")]
        for _ in range(ctx.rounds):
            ours = {}
            for injective in ("false", "true"):
                out = os.path.join(ctx.tmp, "arap_out")
                prof = os.path.join(ctx.tmp, "arap_profile.json")
                run([ctx.bin, "run", graph, "--out", out, "--target", "save_log", "--target", "save_metrics",
                     "--no-report", "--set", f"load.path={mesh}", "--set", f"arap.iterations={iters}",
                     "--set", f"arap.injective={injective}", "--set", "arap.tolerance=0",
                     "--profile-json", prof, "-q"])
                log = list(csv.DictReader(open(os.path.join(out, "arap_camelhead/log.csv"))))
                met = next(csv.DictReader(open(os.path.join(out, "arap_camelhead/metrics.csv"))))
                ours[injective] = (profile_ms(prof, "arap"), float(log[-1]["energy"]), int(float(met["flipped"])),
                                   len(log) - 1)
            prefix = os.path.join(ctx.tmp, "igl")
            run([sys.executable, os.path.join(HERE, "arap_libigl.py"), mesh, str(iters), prefix],
                what="arap_libigl.py")
            d = json.load(open(prefix + ".json"))
            peer_ms = d["harmonic_ms"] + d["precompute_ms"] + d["log"][-1]["elapsed_ms"]
            for injective, label in (("false", "plain"), ("true", "fold-free")):
                ms, energy, flips, ran = ours[injective]
                cases.add(f"{name} ({d['faces']:,} faces), {label}, {iters} iterations", ms, peer_ms,
                          {"energy_ours": energy, "energy_peer": float(d["log"][-1]["energy_raw"]),
                           "flips_ours": flips, "flips_peer": d["log"][-1]["flips"], "iterations_ours": ran})
    return cases.done(), {"peer": pkg_version("libigl"), "threads": "both: all cores",
                          "ours": "arap node (Tutte start + setup + iterations)",
                          "peer_side": "igl.harmonic + arap_precomputation + arap_solve (plain)"}


def _igea_scene(ctx):
    """assets/cornell/cornell_box.obj with the igea scan (assets/meshes/igea_front.obj, 154k
    faces) added as a white diffuse object, scaled so its largest extent is 0.8 and its
    bounding box centred at (0, -0.2, 0.2): the scene `cargo bench --bench trace -- --scene
    igea` builds and `trace_mitsuba.py --scene igea` gives Mitsuba. Written once per run."""
    path = os.path.join(ctx.shared, "cornell_igea", "cornell_igea.obj")
    if os.path.exists(path):
        return path
    os.makedirs(os.path.dirname(path))
    shutil.copy(os.path.join(ROOT, "assets/cornell/cornell_box.mtl"), os.path.dirname(path))
    box = open(os.path.join(ROOT, "assets/cornell/cornell_box.obj")).read()
    nv = sum(1 for ln in box.splitlines() if ln.startswith("v "))
    v, f = [], []
    for ln in open(os.path.join(ROOT, "assets/meshes/igea_front.obj")):
        if ln.startswith("v "):
            v.append([float(x) for x in ln.split()[1:4]])
        elif ln.startswith("f "):
            f.append([int(c.split("/")[0]) for c in ln.split()[1:]])
    lo = [min(p[k] for p in v) for k in range(3)]
    hi = [max(p[k] for p in v) for k in range(3)]
    s = 0.8 / max(hi[k] - lo[k] for k in range(3))
    at = [0.0, -0.2, 0.2]
    with open(path, "w") as out:
        out.write(box.rstrip("\n") + "\no igea\nusemtl white\n")
        for p in v:
            out.write("v %.9g %.9g %.9g\n" % tuple((p[k] - 0.5 * (lo[k] + hi[k])) * s + at[k] for k in range(3)))
        for face in f:
            out.write("f " + " ".join(str(i + nv if i > 0 else i) for i in face) + "\n")
    return path


def _trace_reference(ctx, scene, scene_path):
    """The 1024-spp MIS reference of bench/graphs/trace_cornell_spp.json (256 spp under
    --smoke) for `scene`, rendered once per invocation and shared by both Mitsuba
    comparisons."""
    spp = 256 if ctx.smoke else 1024
    path = os.path.join(ctx.shared, f"reference_{scene}_{spp}", "trace_cornell_spp_reference.exr")
    if not os.path.exists(path):
        run([ctx.bin, "run", os.path.join(ROOT, "bench/graphs/trace_cornell_spp.json"),
             "--target", "save_reference", "--set", f"reference.spp={spp}", "--no-report", "-q",
             *(["--set", f"scene.path={scene_path}"] if scene_path else []),
             "--out", os.path.dirname(path)])
    return path, spp


def _mitsuba(ctx, variant):
    need("mitsuba", "numpy")
    if variant.startswith("llvm"):
        ensure_llvm()
    import numpy as np
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    load = lambda p: np.array(mi.Bitmap(p).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False),  # noqa: E731
                              dtype=np.float64)
    mask = np.array(mi.Bitmap(os.path.join(ROOT, "bench/graphs/trace_cornell_spp_mask.png")), dtype=np.float64)
    graph = os.path.join(ROOT, "bench/graphs/trace_cornell_spp.json")
    igea = os.path.join(ROOT, "assets/meshes/igea_front.obj")
    scenes = [("box", None)] + ([] if ctx.smoke else [("igea", _igea_scene(ctx))])
    spps = [4] if ctx.smoke else [16, 64]
    cases = Cases()
    prep = {}  # case -> each round's scene preparation (ms), from the node's log
    for scene, scene_path in scenes:
        ref_path, ref_spp = _trace_reference(ctx, scene, scene_path)
        ref = load(ref_path)
        keep = mask.reshape(ref.shape[0], ref.shape[1], -1)[..., 0] > 127
        rmse = lambda img: float(np.sqrt(np.mean((img[keep] - ref[keep]) ** 2)))  # noqa: E731
        label = "Cornell box" if scene == "box" else "Cornell box with igea (154k faces)"
        for _ in range(ctx.rounds):
            for spp in spps:
                out = os.path.join(ctx.tmp, "ours")
                prof = os.path.join(ctx.tmp, "trace_profile.json")
                log = run([ctx.bin, "run", graph, "--target", "save", "--set", f"render.spp={spp}", "--no-report",
                           *(["--set", f"scene.path={scene_path}"] if scene_path else []),
                           "--out", out, "--profile-json", prof], both=True)
                ours_ms = profile_ms(prof, "render")
                m = re.search(r"render: .*scene (?:prepared|reused from the last render) in ([0-9.]+) s", log)
                if not m:
                    raise Failed("render_path's log does not say how long the scene preparation took")
                e_ours = rmse(load(os.path.join(out, "trace_cornell_spp.exr")))
                mdir = os.path.join(ctx.tmp, "mitsuba")
                run([sys.executable, os.path.join(HERE, "trace_mitsuba.py"), "--spp", str(spp),
                     "--variants", variant, "--scene", scene, "--igea", igea, "--out", mdir],
                    env=script_env(ctx), what="trace_mitsuba.py")
                runs = [r for r in json.load(open(os.path.join(mdir, "mitsuba.json")))["runs"]
                        if r["variant"] == variant and r["spp"] == spp and r.get("scene", "box") == scene]
                if not runs:
                    raise Failed(f"trace_mitsuba.py rendered nothing with {variant} (variant unavailable?)")
                e_peer = rmse(load(os.path.join(mdir, runs[0]["exr"])))
                case = f"{label} 256x256, {spp} spp, MIS"
                prep.setdefault(case, []).append(float(m.group(1)) * 1e3)
                cases.add(case, ours_ms, runs[0]["seconds"] * 1e3,
                          {"rmse_ours": e_ours, "rmse_peer": e_peer, "reference_spp": ref_spp})
    rows = cases.done()
    for r in rows:
        # The peer's time excludes its scene's load and BVH build: ours without the
        # preparation (flattening, shading normals, BVH) as well, round by round.
        rest = [o - p for o, p in zip(r["ours_ms"], prep.get(r["case"], []))]
        if rest and r.get("median_peer_ms"):
            r["ours_prepare_ms"] = prep[r["case"]]
            r["median_ours_render_ms"] = statistics.median(rest)
            r["render_ratio"] = r["median_ours_render_ms"] / r["median_peer_ms"]
    return rows, {"peer": f"{pkg_version('mitsuba')} {variant}", "threads": "both: all cores",
                          "ours": "render_path node (wall time, scene preparation included)",
                          "peer_side": "mi.render (after a warm-up render; scene loaded before)"}


def c_mitsuba_scalar(ctx):
    """Path tracing mi.cornell_box() (256x256, max_depth 8, box filter), empty and with the
    154k-face igea scan standing in it, with cgnodes' render_path
    (bench/graphs/trace_cornell_spp.json) and Mitsuba 3's scalar_rgb
    (bench/peers/trace_mitsuba.py), equal spp. Times: the render_path node's wall time, which
    includes preparing the scene (BVH build, shading normals), against mi.render after a
    warm-up render, the scene loaded (and its BVH built) before; the record also gives ours
    without the scene preparation (the time the node logs for it subtracted, round by round),
    timed as the peer is. Accuracy: RMSE of each
    against cgnodes' 1024-spp MIS reference of the same scene, light masked
    (bench/graphs/trace_cornell_spp_mask.png)."""
    return _mitsuba(ctx, "scalar_rgb")


def c_mitsuba_llvm(ctx):
    """As mitsuba_scalar, with Mitsuba 3's llvm_ad_rgb (Dr.Jit's LLVM JIT, wavefront)."""
    return _mitsuba(ctx, "llvm_ad_rgb")


def c_opencv_seamless(ctx):
    """poisson_blend (seamless and mixed gradients) against OpenCV's seamlessClone, twelve
    chained pastes per case (bench/peers/poisson_opencv.py): cgnodes' first paste (a new mask
    shape) and its median paste with the factor reused, each against OpenCV's median call of
    the same round. Accuracy: mean 8-bit difference over the mask (by design: OpenCV solves
    on sRGB bytes, cgnodes on linear values)."""
    need("cv2", "numpy")
    return _script_cases(ctx, "poisson_opencv.py", [], {"ours": "poisson_blend node (--profile-json)",
                                                         "peer_side": "cv2.seamlessClone"})


def _script_cases(ctx, script, args, extra, env=None):
    cases, version, more = Cases(), None, {}
    for _ in range(ctx.rounds):
        res = script_round(ctx, script, *args, env=env)
        for c in res["cases"]:
            cases.add(c["case"], c["ours_ms"], c["peer_ms"], c.get("accuracy"))
        version = res.get("peer_version", version)
        more = {k: v for k, v in res.items() if k not in ("cases", "peer_version")}
    return cases.done(), {"peer": version, **more, **extra}


def c_skimage_tps(ctx):
    """image_warp (rbf, thin_plate, inverse) against scikit-image's
    ThinPlateSplineTransform + warp(order=1) on a 1024x1024 image with 32 control points
    (bench/peers/warp_skimage.py). Times: the node's own time against estimate + warp.
    Accuracy: largest difference per channel in 1/255 where ours is valid."""
    need("skimage", "numpy")
    cases, version = Cases(), None
    for _ in range(ctx.rounds):
        r = script_round(ctx, "warp_skimage.py", ctx.bin, 1)
        cases.add("1024x1024 RGB, 32 control points", r["cgnodes_node_s_median"] * 1e3,
                  r["skimage_s_median"] * 1e3,
                  {"max_diff_255": r["max_diff_255"], "pixels_over_1_255": r["pixels_over_1_255"],
                   "max_diff_255_vs_exact_tps": r["max_diff_255_vs_exact_tps_warp"],
                   "cgnodes_run_wall_ms": r["cgnodes_run_wall_s_median"] * 1e3})
        version = "scikit-image " + r["skimage_version"]
    return cases.done(), {"peer": version, "threads": "both: all cores",
                          "ours": "image_warp node time", "peer_side": "estimate + skimage.transform.warp"}


def c_seam_carving(ctx):
    """seam_carve against PyPI seam-carving (numba DP), removing 25 % of the columns, backward
    and forward energy (bench/peers/seam_carving_peer.py). Accuracy: the share of removed
    pixels both remove, on the colour image and on the peer's own grey image."""
    need("seam_carving", "numpy")
    return _script_cases(ctx, "seam_carving_peer.py", [], {
        "peer": pkg_version("seam-carving"), "threads": "both: one", "ours": "seam_carve node time", "peer_side": "seam_carving.resize"})


def c_numpy_svd(ctx):
    """image_svd (rank 50, full and randomized) against numpy.linalg.svd + reconstruction on a
    1024x1024 channel (bench/peers/svd_numpy.py), both on one thread. Accuracy: PSNR of the
    rank-50 image."""
    need("numpy")
    return _script_cases(ctx, "svd_numpy.py", [], env=ONE_THREAD, extra={
        "threads": "both: one (cgnodes --threads 1, OPENBLAS_NUM_THREADS=1)",
        "ours": "image_svd node time", "peer_side": "np.linalg.svd + rank-50 product"})


def c_numpy_rpca(ctx):
    """rpca against the course's numpy ADMM (SVD thresholding), equal iterations, 500x500
    rank 25 with 5 % gross errors (bench/peers/rpca_numpy.py), both on one thread. Accuracy:
    relative error of the recovered low-rank matrix for both, and between them."""
    need("numpy")
    return _script_cases(ctx, "rpca_numpy.py", [5 if ctx.smoke else 60], env=ONE_THREAD, extra={
        "threads": "both: one (cgnodes --threads 1, OPENBLAS_NUM_THREADS=1)",
        "ours": "rpca node iterations (time_ms)", "peer_side": "numpy ADMM loop"})


def c_scipy_splines(ctx):
    """curve_interpolate and data_fit against scipy's CubicSpline (natural, clamped,
    not-a-knot, periodic), BarycentricInterpolator, RBFInterpolator, numpy.polyfit and
    scikit-learn's Ridge (bench/peers/curves_scipy.py). Accuracy only: both sides take
    microseconds on a dozen points, so no time is compared."""
    need("scipy", "numpy", "sklearn")
    r = script_round(ctx, "curves_scipy.py", ctx.bin)
    cases = Cases()
    for name, v in r.get("curves_max_diff_rel_bbox", {}).items():
        cases.add(f"curve {name}", None, None, {"max_diff_rel_bbox": v})
    cases.add("data_fit polynomial (degree 5)", None, None, {"rel_diff": r["polyfit_rel_diff"]})
    cases.add("data_fit ridge", None, None, {"rel_diff": r["ridge_rel_diff"]})
    if not r.get("pass"):
        raise Failed(f"curves_scipy.py: largest difference {r.get('worst')} above 1e-9")
    return cases.done(), {"peer": f"{pkg_version('scipy')}, {pkg_version('scikit-learn')}",
                          "ours": "curve_interpolate, data_fit", "peer_side": "scipy.interpolate, numpy, sklearn"}


def c_sklearn_mlp(ctx):
    """classifier_train (MLP, Adam, 200 epochs) against scikit-learn's MLPClassifier with the
    same layers, learning rate, batch and epochs on the course's insects data
    (bench/peers/insects_sklearn.py, seed 0), both on one thread. Accuracy: test accuracy on
    all 210 points."""
    need("sklearn", "numpy")
    cases, version = Cases(), None
    for _ in range(ctx.rounds):
        r = script_round(ctx, "insects_sklearn.py", ctx.bin, 1, env=ONE_THREAD)
        cases.add("insects, 200 epochs, seed 0", r["mean_seconds"]["ours"] * 1e3, r["mean_seconds"]["sklearn"] * 1e3,
                  {"test_accuracy_ours": r["mean_all210"]["ours"], "test_accuracy_peer": r["mean_all210"]["sklearn"]})
        version = "scikit-learn " + r["sklearn"]
    return cases.done(), {"peer": version, "threads": "both: one (cgnodes --threads 1, OPENBLAS_NUM_THREADS=1)",
                          "ours": "classifier_train's train_seconds", "peer_side": "MLPClassifier.fit"}


def _cloth_graph(n):
    s = 0.1 * (n - 1)
    return {"format": "cgnodes-graph", "version": 1, "nodes": {
        "grid": {"type": "mesh_grid", "params": {"cells_u": n - 1, "cells_v": n - 1, "size": [s, s], "plane": "xz",
                                                 "center": [s / 2, 0.0, s / 2], "triangles": False}},
        "cloth": {"type": "mass_spring", "inputs": {"mesh": "grid.mesh"}, "params": {
            "integrator": "semi_implicit", "stiffness": 1000.0, "h": 1.0 / 60 / 16, "substeps": 16,
            "damped": False, "gravity": -9.81, "gravity_axis": "y", "mass": 0.1 * n * n,
            "shear": True, "bending": True, "fixed": f"0,{n - 1}", "profile": True}}}}


def c_warp_cloth(ctx):
    """mass_spring (semi_implicit) against NVIDIA Warp's own CPU cloth benchmark
    (bench/peers/cloth_warp.py: warp/examples/benchmarks/benchmark_cloth.py, warp_cpu): an
    n x n grid, spacing 0.1, stretch, shear and bending springs k = 1000, 0.1 kg per particle,
    two corners fixed, 60 frames of 16 substeps. cgnodes runs the same set-up as a graph
    (mesh_grid -> mass_spring, f64, no dashpot) and logs each frame's time; both sides give
    the fastest frame (Warp's `min`, which leaves out its kernel loading). No accuracy figure:
    Warp's script returns no positions."""
    need("warp", "pxr", "numpy")
    sizes = [32] if ctx.smoke else [32, 64, 128]
    cases, version = Cases(), None
    for _ in range(ctx.rounds):
        for n in sizes:
            g = os.path.join(ctx.tmp, f"cloth{n}.json")
            json.dump(_cloth_graph(n), open(g, "w"))
            out = run([ctx.bin, "run", g, "--frames", "1..61", "--target", "cloth", "--no-report",
                       "--out", os.path.join(ctx.tmp, "cloth_out")], env=script_env(ctx), both=True)
            frames = [float(m) for m in re.findall(r"frame took ([0-9.]+) ms", out)]
            if len(frames) < 30:
                raise Failed(f"cloth graph logged {len(frames)} frame times")
            w = script_round(ctx, "cloth_warp.py", str(n))
            version = "warp-lang " + str(w.get("version"))
            cases.add(f"{n}x{n} grid, fastest frame", min(frames), w[str(n)]["min"],
                      {"ours_median_frame_ms": statistics.median(frames), "peer_avg_frame_ms": w[str(n)]["avg"]})
    return cases.done(), {"peer": version, "threads": "cgnodes: all cores (f64); Warp: CPU device (f32)",
                          "ours": "mass_spring frame time (profile log)", "peer_side": "benchmark_cloth.py warp_cpu"}


def c_splishsplash(ctx):
    """sph_fluid (DFSPH, Akinci boundary particles) against SPlisHSPlasH's DFSPH (PyPI
    pysplishsplash, bench/peers/sph_splishsplash.py) on the 2-D Martin & Moyce dam break to
    T = 3.5, same particle radius, CFL 0.4. Times: the simulation alone on both sides.
    Accuracy: the front's RMS relative error in T against Martin & Moyce's table
    (bench/peers/sph_front.py, as compare_series computes it)."""
    import csv
    import sph_front
    radii = [0.025] if ctx.smoke else [0.01, 0.005]
    env = script_env(ctx)
    # as bench/sweeps/sph_dam_break.sh: the wheel needs libGLdispatch preloaded, and OpenMP
    # threads that wait passively on a shared machine
    env["LD_PRELOAD"] = "/lib/x86_64-linux-gnu/libGLdispatch.so.0"
    env.setdefault("OMP_WAIT_POLICY", "PASSIVE")
    need("pysplishsplash", "numpy", env=env)
    cases = Cases()
    for _ in range(ctx.rounds):
        for r in radii:
            out_csv = os.path.join(ctx.tmp, "sph.csv")
            run([ctx.bin, "sweep", os.path.join(ROOT, "bench/graphs/sph_dam_break.json"), "--frames", "0..112",
                 "--set", f"fluid.particle_radius={r}", "--set", "fluid.solver=dfsph",
                 "--measure", "front_error.error", "--csv", out_csv])
            row = next(csv.DictReader(open(out_csv)))
            if row["status"] != "ok":
                raise Failed(f"cgnodes sph sweep: {row['error']}")
            p = run([sys.executable, os.path.join(HERE, "sph_splishsplash.py"), str(r), "3.5", "dfsph"],
                    env=env, what="sph_splishsplash.py")
            d = json.loads([ln for ln in p.splitlines() if ln.startswith("{")][-1])
            cases.add(f"dam break to T = 3.5, r = {r} m", float(row["ms:fluid"]), d["seconds"] * 1e3,
                      {"front_error_ours": float(row["front_error.error"]),
                       "front_error_peer": sph_front.front_error([tuple(x) for x in d["front"]]),
                       "particles_peer": d["particles"], "steps_peer": d["steps"]})
    return cases.done(), {"peer": pkg_version("pysplishsplash"), "threads": "both: all cores",
                          "ours": "sph_fluid node time (sum over frames)", "peer_side": "SPlisHSPlasH simulation loop"}


def c_usd_skin(ctx):
    """Linear blend skinning of a tube (4 influences, 8 joints, 8 animated frames): cgnodes'
    lbs_points (and dual quaternions) against usd-core's UsdSkel.SkinPointsLBS on the same
    points, weights and joint transforms (`cargo bench --bench skin`, which hands them to
    bench/peers/skin_usd.py). Accuracy: largest coordinate difference between the two, relative
    to the bounding box diagonal."""
    need("pxr", "numpy")
    if not shutil.which("cargo"):
        raise Missing("cargo (to run bench/skin.rs)")
    verts = 20000 if ctx.smoke else 100000
    env = script_env(ctx)
    env.update(SKIN_VERTICES=str(verts), SKIN_FRAMES="8", SKIN_REPEAT="1" if ctx.smoke else "5")
    cases = Cases()
    for _ in range(ctx.rounds):
        out = run(["cargo", "bench", "--quiet", "-p", "cgnodes", "--bench", "skin"], env=env, cwd=ROOT,
                  what="cargo bench --bench skin")
        lbs = re.search(r"cgnodes LBS: ([0-9.]+) ms/frame", out)
        dqs = re.search(r"cgnodes DQS: ([0-9.]+) ms/frame", out)
        peer = re.search(r"usd-core SkinPointsLBS: ([0-9.]+) ms/frame .*largest difference ([0-9.e+-]+) of", out)
        if not (lbs and peer):
            raise Failed("cargo bench --bench skin: no usd-core line:\n" + out[-800:])
        acc = {"max_rel_diff": float(peer.group(2))}
        cases.add(f"{verts} vertices, LBS", float(lbs.group(1)), float(peer.group(1)), acc)
        cases.add(f"{verts} vertices, cgnodes DQS vs usd-core LBS", float(dqs.group(1)), float(peer.group(1)))
    return cases.done(), {"peer": pkg_version("usd-core"), "threads": "cgnodes: rayon's default; usd-core: its own",
                          "ours": "lbs_points / dqs (ms per frame)", "peer_side": "UsdSkel.SkinPointsLBS"}


COMPARISONS = {
    "tutte_libigl": c_tutte_libigl,
    "arap_libigl": c_arap_libigl,
    "arap_hard_libigl": c_arap_hard_libigl,
    "mitsuba_scalar": c_mitsuba_scalar,
    "mitsuba_llvm": c_mitsuba_llvm,
    "opencv_seamless": c_opencv_seamless,
    "skimage_tps": c_skimage_tps,
    "seam_carving": c_seam_carving,
    "numpy_svd": c_numpy_svd,
    "numpy_rpca": c_numpy_rpca,
    "scipy_splines": c_scipy_splines,
    "sklearn_mlp": c_sklearn_mlp,
    "warp_cloth": c_warp_cloth,
    "splishsplash": c_splishsplash,
    "usd_skin": c_usd_skin,
}


# ----------------------------------------------------------------------------- main

class Ctx:
    pass


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--smoke", action="store_true", help="small sizes, one round, records in target/peers-smoke/")
    ap.add_argument("--only", action="append", default=[], help="NAME[,NAME...] (repeatable)")
    ap.add_argument("--rounds", type=int, default=None, help="rounds per comparison (default 5; 1 with --smoke)")
    ap.add_argument("--skip-missing", action="store_true",
                    help="write a missing or failing peer's record as 'not measured' instead of failing")
    ap.add_argument("--list", action="store_true", help="print the comparisons and exit")
    ap.add_argument("--out", default=None, help="record folder (default bench/results, or target/peers-smoke)")
    ap.add_argument("--no-install", action="store_true", help="use the running Python as it is")
    a = ap.parse_args()
    names = [n for o in a.only for n in o.split(",") if n]
    if a.list:
        for n, f in COMPARISONS.items():
            print(f"{n:16s} {f.__doc__.strip().splitlines()[0]}")
        return 0
    unknown = [n for n in names if n not in COMPARISONS]
    if unknown:
        print(f"unknown comparison(s): {', '.join(unknown)}; --list names them", file=sys.stderr)
        return 2
    if not a.no_install and not in_venv() and not os.environ.get("PEERS_IN_VENV"):
        install_and_reexec()
    ctx = Ctx()
    ctx.smoke = a.smoke
    ctx.rounds = a.rounds or (1 if a.smoke else 5)
    out_dir = a.out or os.path.join(ROOT, "target/peers-smoke" if a.smoke else "bench/results")
    ctx.shared = tempfile.mkdtemp(prefix="cgnodes-peers-")
    failed, t_all = [], time.perf_counter()
    for name in names or COMPARISONS:
        fn = COMPARISONS[name]
        print(f"== {name}: {fn.__doc__.strip().splitlines()[0]}", flush=True)
        t0 = time.perf_counter()
        ctx.tmp = tempfile.mkdtemp(prefix=f"cgnodes-{name}-")
        status, reason, cases, extra = "measured", None, [], {}
        try:
            ctx.bin = cgnodes_bin()
            cases, extra = fn(ctx)
        except (Missing, Failed, Exception) as e:  # noqa: BLE001
            kind = "missing" if isinstance(e, Missing) else "failed"
            reason = f"{kind}: {e}"
            if not isinstance(e, (Missing, Failed)):
                reason += "\n" + traceback.format_exc(limit=3)
            status = "not measured"
            print(f"   {name}: {reason}", file=sys.stderr, flush=True)
        finally:
            shutil.rmtree(ctx.tmp, ignore_errors=True)
        secs = time.perf_counter() - t0
        if status != "measured" and not a.skip_missing:
            failed.append(name)
            continue
        for c in cases:
            if c.get("ratio") is not None:
                print(f"   {c['case']}: ours {c['median_ours_ms']:.1f} ms, peer {c['median_peer_ms']:.1f} ms, "
                      f"ratio {c['ratio']:.2f}; {c['accuracy']}", flush=True)
            else:
                print(f"   {c['case']}: {c['accuracy']}", flush=True)
        rerun = f"bench/run_all --peers --only {name}" + (" --smoke" if a.smoke else "") + \
            (f" --rounds {a.rounds}" if a.rounds else "")
        path = _record.write(name, rerun, out_dir=out_dir, status=status, reason=reason, smoke=a.smoke, rounds=ctx.rounds,
                             method=" ".join(fn.__doc__.split()), seconds=round(secs, 1), **extra, cases=cases)
        print(f"   {status} in {secs:.0f} s -> {os.path.relpath(path, ROOT)}", flush=True)
    shutil.rmtree(ctx.shared, ignore_errors=True)
    print(f"all comparisons: {time.perf_counter() - t_all:.0f} s")
    if failed:
        print(f"failed or missing peers: {', '.join(failed)} (--skip-missing records them as not measured)",
              file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
