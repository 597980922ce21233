"""NVIDIA Warp's own CPU cloth benchmark (warp/examples/benchmarks/benchmark_cloth.py, mode
warp_cpu: 32^2, 64^2, 128^2 grids, 60 frames of 16 substeps, k = 1000), run unchanged; prints
its milliseconds per frame as JSON: {"32": {"min": ms, "avg": ms}, ..., "version": "..."}.
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
    os.execve(py, [py, os.path.abspath(__file__)], env)


def main():
    ensure_warp()
    import warp

    script = os.path.join(os.path.dirname(warp.__file__), "examples", "benchmarks", "benchmark_cloth.py")
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
