#!/usr/bin/env python3
"""Test plugin for cgnodes (standard library only): one node that works and nodes that fail in
the ways the runtime must contain. The node type in the request selects the behaviour."""

import json
import subprocess
import sys
import time

req = json.load(sys.stdin)
node = req["node"]
inp = req["inputs"]


def reply(outputs, **extra):
    json.dump({"protocol": 1, "outputs": outputs, **extra}, sys.stdout)


if node == "pl_echo":
    out = {"y": 2 * inp["x"], "n": inp["n"], "v": inp["v"], "s": inp["s"], "xs": inp["xs"]}
    if "mesh" in inp:
        m = inp["mesh"]
        out["mesh"] = {"positions": m["positions"], "face_counts": m["face_counts"],
                       "face_indices": m["face_indices"], "uvs": m.get("uvs"),
                       "uv_domain": m.get("uv_domain"), "attributes": m["attributes"]}
        if out["mesh"]["uvs"] is None:
            del out["mesh"]["uvs"]
    if "image" in inp:
        out["image"] = {"pixels": inp["image"]["pixels"]}
    if "points" in inp:
        out["points"] = inp["points"]
    if "table" in inp:
        out["table"] = inp["table"]
    if "camera" in inp:
        out["camera"] = inp["camera"]
    print("echo: sent everything back", file=sys.stderr)
    reply(out, log=["echo ran"])
elif node == "pl_crash":
    print("about to divide by zero", file=sys.stderr)
    print(1 / inp["x"])
elif node == "pl_hang":
    print("hanging now", file=sys.stderr, flush=True)
    # A child that inherits the pipes: the runtime must kill it too, not wait for it.
    child = subprocess.Popen(["sleep", "3600"])
    if inp["pidfile"]:
        with open(inp["pidfile"], "w") as f:
            f.write(str(child.pid))
    time.sleep(3600)
elif node == "pl_wrong_type":
    reply({"count": "three"})
elif node == "pl_wrong_shape":
    reply({"mesh": {"base": "mesh", "positions": inp["mesh"]["face_counts"]}})
elif node == "pl_escape":
    reply({"mesh": {"base": "mesh", "positions": "/etc/passwd"}})
elif node == "pl_bad_json":
    print("this is not JSON")
elif node == "pl_bad_protocol":
    json.dump({"protocol": 99, "outputs": {"y": 1.0}}, sys.stdout)
elif node == "pl_missing_output":
    reply({})
elif node == "pl_reported_error":
    print("checking the input", file=sys.stderr)
    json.dump({"protocol": 1, "error": "the input mesh must be closed"}, sys.stdout)
    sys.exit(2)
elif node == "pl_counter":
    state = req.get("state") or {"count": 0}
    state["count"] += 1
    reply({"count": state["count"], "frame": req["frame"]}, state=state)
elif node == "pl_write":
    with open(inp["path"], "w") as f:
        f.write(inp["text"])
    reply({"bytes": len(inp["text"].encode())})
else:
    sys.exit(f"unknown node {node}")
