"""The record a benchmark script writes: bench/results/NAME.json with the command, commit,
date and machine beside the script's own fields (shared by bench/*.py)."""
import json
import os
import platform
import subprocess
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _cpu_model():
    """The processor's name from /proc/cpuinfo (Linux), else None."""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return None


def write(name, command, out_dir=None, **fields):
    """Writes bench/results/NAME.json (or OUT_DIR/NAME.json) and returns its path."""
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    rec = {
        "benchmark": name,
        "command": command,
        "commit": commit,
        "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "machine": {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
                    "model": _cpu_model(), "load_average": [round(x, 2) for x in os.getloadavg()]},
        **fields,
    }
    path = os.path.join(out_dir or os.path.join(ROOT, "bench/results"), name + ".json")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        json.dump(rec, f, indent=1)
    return path
