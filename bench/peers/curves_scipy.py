#!/usr/bin/env python3
"""scipy, numpy and scikit-learn against cgnodes' `curve_interpolate` and `data_fit` (issue 26).

Usage: curves_scipy.py [CGNODES_BINARY]

Runs one cgnodes graph on the shipped data (assets/curves/points12.txt, the dozen points of
graphs/curve_interpolation.json; assets/curves/noisy_sine.csv, the samples of
graphs/data_fit.json) that writes every curve's samples (t, x, y) and every fit's
coefficients as CSV, and evaluates the peers at the same parameters:
- `scipy.interpolate.CubicSpline(t, P, bc_type=...)` for natural, clamped (zero slopes),
  not-a-knot, and periodic (the closed polygon: the first point appended, chordal t);
- `scipy.interpolate.BarycentricInterpolator(t, P)` for the polynomial;
- `scipy.interpolate.RBFInterpolator(t, P, kernel=..., epsilon=1/scale, degree=1)` for the
  gaussian, multiquadric and thin-plate kernels;
- `numpy.polyfit(x, y, 5)` and `sklearn.linear_model.Ridge(alpha=lambda, fit_intercept=False,
  solver="svd")` on the columns 1, x, ..., x^12 for data_fit's polynomial and ridge models.

Curves are compared as the largest coordinate difference over the samples divided by the
diagonal of the points' bounding box; coefficients as |ours - theirs| / |theirs| (2-norms).
The chordal parameter values are computed here too and compared with curve_parameterize's.
Prints one JSON object and exits 1 if any difference exceeds 1e-9.

Needs numpy, scipy and scikit-learn; when one is missing the script installs them into
target/peers-venv (PyPI) and re-runs itself there.
"""
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import _images  # noqa: E402  (the peers' virtual environment and the cgnodes binary)
TOL = 1e-9


CURVES = {
    "natural": {"method": "cubic_spline", "end": "natural"},
    "clamped": {"method": "cubic_spline", "end": "clamped"},
    "not_a_knot": {"method": "cubic_spline", "end": "not_a_knot"},
    "periodic": {"method": "cubic_spline", "end": "periodic"},
    "polynomial": {"method": "polynomial"},
    "rbf_gaussian": {"method": "rbf", "kernel": "gaussian", "scale": 0.15},
    "rbf_multiquadric": {"method": "rbf", "kernel": "multiquadric", "scale": 0.15},
    "rbf_thin_plate": {"method": "rbf", "kernel": "thin_plate", "scale": 1.0},
}
DEGREE, RIDGE_DEGREE, LAMBDA = 5, 12, 1e-4


def graph(points, samples):
    nodes = {
        "load": {"type": "points_load", "params": {"path": points}},
        "t": {"type": "curve_parameterize", "params": {"method": "chordal"},
              "inputs": {"points": "load.points"}},
        "wt": {"type": "table_write", "params": {"path": "t.csv"}, "inputs": {"value": "t.t"}},
        "data": {"type": "points_load",
                 "params": {"path": os.path.join(ROOT, "assets/curves/noisy_sine.csv"),
                            "x_column": "x", "y_column": "y"}},
        "poly": {"type": "data_fit", "params": {"model": "polynomial", "degree": DEGREE},
                 "inputs": {"points": "data.points"}},
        "ridge": {"type": "data_fit",
                  "params": {"model": "ridge", "degree": RIDGE_DEGREE, "lambda": LAMBDA},
                  "inputs": {"points": "data.points"}},
        "wpoly": {"type": "table_write", "params": {"path": "poly.csv"},
                  "inputs": {"value": "poly.coefficients"}},
        "wridge": {"type": "table_write", "params": {"path": "ridge.csv"},
                   "inputs": {"value": "ridge.coefficients"}},
    }
    for name, params in CURVES.items():
        p = dict(params, samples=samples)
        inputs = {"points": "load.points"}
        if name != "periodic":
            inputs["t"] = "t.t"
        nodes[name] = {"type": "curve_interpolate", "params": p, "inputs": inputs}
        nodes["w_" + name] = {"type": "table_write", "params": {"path": name + ".csv"},
                              "inputs": {"value": name + ".table"}}
    return {"format": "cgnodes-graph", "version": 1, "nodes": nodes}


def main():
    _images.ensure(["numpy", "scipy", "sklearn"], ["numpy", "scipy", "scikit-learn"], __file__, "CURVES_SCIPY_REEXEC")
    import numpy as np
    import scipy
    import sklearn
    from scipy.interpolate import BarycentricInterpolator, CubicSpline, RBFInterpolator
    from sklearn.linear_model import Ridge

    cg = sys.argv[1] if len(sys.argv) > 1 else _images.cgnodes_bin()
    pts_file = os.path.join(ROOT, "assets/curves/points12.txt")
    P = np.loadtxt(pts_file)
    diag = np.hypot(*(P.max(axis=0) - P.min(axis=0)))

    def chordal(Q):
        d = np.hypot(*np.diff(Q, axis=0).T)
        return np.concatenate([[0.0], np.cumsum(d)]) / d.sum()

    t = chordal(P)
    closed = np.vstack([P, P[:1]])
    tc = chordal(closed)
    with tempfile.TemporaryDirectory() as d:
        gpath = os.path.join(d, "g.json")
        with open(gpath, "w") as f:
            json.dump(graph(pts_file, 1001), f)
        subprocess.run([cg, "run", gpath, "--out", d], check=True, capture_output=True)
        read = lambda n: np.loadtxt(os.path.join(d, n), delimiter=",", skiprows=1, ndmin=2)
        ours_t = read("t.csv")[:, 0]
        out = {"cgnodes": cg, "numpy": np.__version__, "scipy": scipy.__version__,
               "sklearn": sklearn.__version__, "points": len(P), "samples": 1001,
               "chordal_t_max_diff": float(np.abs(ours_t - t).max())}
        peers = {
            "natural": lambda: CubicSpline(t, P, bc_type="natural"),
            "clamped": lambda: CubicSpline(t, P, bc_type="clamped"),
            "not_a_knot": lambda: CubicSpline(t, P, bc_type="not-a-knot"),
            "periodic": lambda: CubicSpline(tc, closed, bc_type="periodic"),
            "polynomial": lambda: BarycentricInterpolator(t, P),
            "rbf_gaussian": lambda: RBFInterpolator(t[:, None], P, kernel="gaussian",
                                                    epsilon=1 / 0.15, degree=1),
            "rbf_multiquadric": lambda: RBFInterpolator(t[:, None], P, kernel="multiquadric",
                                                        epsilon=1 / 0.15, degree=1),
            "rbf_thin_plate": lambda: RBFInterpolator(t[:, None], P,
                                                      kernel="thin_plate_spline", degree=1),
        }
        worst = 0.0
        curves = {}
        for name, make in peers.items():
            tab = read(name + ".csv")
            ts, xy = tab[:, 0], tab[:, 1:3]
            peer = make()
            ref = peer(ts[:, None]) if name.startswith("rbf") else peer(ts)
            rel = float(np.abs(xy - ref).max() / diag)
            curves[name] = rel
            worst = max(worst, rel)
        out["curves_max_diff_rel_bbox"] = curves

        data = np.loadtxt(os.path.join(ROOT, "assets/curves/noisy_sine.csv"), delimiter=",",
                          skiprows=3)
        x, y = data[:, 0], data[:, 1]
        ours_poly = read("poly.csv")[:, 0]
        ref_poly = np.polyfit(x, y, DEGREE)[::-1]
        cols = np.vander(x, RIDGE_DEGREE + 1, increasing=True)
        ref_ridge = Ridge(alpha=LAMBDA, fit_intercept=False, solver="svd").fit(cols, y).coef_
        ours_ridge = read("ridge.csv")[:, 0]
        rel = lambda a, b: float(np.linalg.norm(a - b) / np.linalg.norm(b))
        out["polyfit_rel_diff"] = rel(ours_poly, ref_poly)
        out["ridge_rel_diff"] = rel(ours_ridge, ref_ridge)
        worst = max(worst, out["polyfit_rel_diff"], out["ridge_rel_diff"])
        out["worst"] = worst
        out["pass"] = bool(worst <= TOL)
    print(json.dumps(out, indent=2))
    sys.exit(0 if out["pass"] else 1)


if __name__ == "__main__":
    main()
