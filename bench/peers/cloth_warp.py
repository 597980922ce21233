"""NVIDIA Warp's own CPU cloth benchmark (warp/examples/benchmarks/benchmark_cloth.py, mode
warp_cpu: 32^2, 64^2, 128^2 grids, 60 frames of 16 substeps, k = 1000), run unchanged; prints
its milliseconds per frame as JSON: {"32": {"min": ms, "avg": ms}, ..., "version": "..."}.
With a first argument "32,64,128,256" the script's own `run_benchmark` (everything above its
"# record profiling information" line, executed as is) is called for those grid sizes instead,
since the script itself stops at 128^2.
The script's average includes the first frame, which loads the compiled kernels; the minimum
is the steady state.

Run by `cargo bench --bench cloth`. Needs `warp-lang` and `usd-core`; when they are missing it
installs them into target/peers-venv (PyPI) and re-runs itself there.
"""
import json
import os
import re
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
VENV = os.path.join(HERE, "..", "..", "target", "peers-venv")


def ensure_warp():
    try:
        import warp  # noqa: F401
        import pxr  # noqa: F401
        return
    except ImportError:
        pass
    if os.environ.get("CLOTH_WARP_REEXEC"):
        sys.exit("warp-lang / usd-core could not be imported after installing them")
    py = os.path.join(VENV, "bin", "python")
    if not os.path.exists(py):
        subprocess.check_call([sys.executable, "-m", "venv", VENV])
    subprocess.check_call([py, "-m", "pip", "install", "--quiet", "warp-lang", "usd-core", "numpy"])
    env = dict(os.environ, CLOTH_WARP_REEXEC="1")
    os.execve(py, [py, os.path.abspath(__file__)] + sys.argv[1:], env)


def run_dims(warp, script, dims):
    """Warp's run_benchmark('warp_cpu', dim) for each dim, timed by its own ScopedTimer."""
    import numpy as np

    src = open(script).read()
    src = src[: src.index("# record profiling information")]
    ns = {"__name__": "benchmark_cloth", "__file__": script}
    sys.path.insert(0, os.path.dirname(script))
    cwd = os.getcwd()
    res = {"version": warp.config.version}
    with tempfile.TemporaryDirectory() as d:
        os.chdir(d)
        try:
            exec(compile(src, script, "exec"), ns)
            timers = {}
            for dim in dims:
                ns["run_benchmark"]("warp_cpu", dim, timers, render=False)
                v = timers["Dim (%d^2)" % dim]
                res[str(dim)] = {"min": float(np.min(v)), "avg": float(np.mean(v))}
        finally:
            os.chdir(cwd)
    return res


def main():
    ensure_warp()
    import warp

    script = os.path.join(os.path.dirname(warp.__file__), "examples", "benchmarks", "benchmark_cloth.py")
    dims = [int(d) for d in sys.argv[1].split(",")] if len(sys.argv) > 1 and sys.argv[1] else None
    if dims is not None and dims != [32, 64, 128]:
        print(json.dumps(run_dims(warp, script, dims)))
        return
    with tempfile.TemporaryDirectory() as d:
        out = subprocess.run([sys.executable, script, "warp_cpu"], cwd=d, capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(out.stdout + out.stderr)
    res = {"version": warp.config.version}
    for dim in (32, 64, 128):
        m = re.search(r"Dim \(%d\^2\)\s+min:\s*([\d.]+)\s+max:\s*([\d.]+)\s+avg:\s*([\d.]+)" % dim, out.stdout)
        if m:
            res[str(dim)] = {"min": float(m.group(1)), "avg": float(m.group(3))}
    print(json.dumps(res))


if __name__ == "__main__":
    main()
