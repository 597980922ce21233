#!/usr/bin/env python3
"""scikit-learn's MLPClassifier against cgnodes' `classifier_train` on the insect data (issue 26).

Usage: insects_sklearn.py [CGNODES_BINARY] [SEEDS]

Same network and training on both sides: hidden layers (16, 16), ReLU, Adam (learning rate
0.01, beta 0.9 / 0.999, eps 1e-8), 200 epochs, batches of 32, shuffled every epoch,
standardized features, no L2 penalty (sklearn `alpha=0`), no early stopping and no
tolerance-based stop (`tol=0`, `n_iter_no_change` = epochs). For seeds 0..SEEDS-1 (default
5) it trains both on assets/insects/insects-training.txt and reports the test accuracy on the
testing file's first 60 rows (also in the training file), on the other 150, and on all 210,
and the training time: sklearn's `fit` (perf_counter) against the `train_seconds` our node
records around its whole execution (reading the table, standardizing, training, and a
training-accuracy pass after every epoch that sklearn does not make). cgnodes runs with one
worker thread, one training node at a time. Prints one JSON object.

Needs numpy and scikit-learn; when one is missing the script installs them into
target/peers-venv (PyPI) and re-runs itself there.
"""
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import _images  # noqa: E402  (the peers' virtual environment and the cgnodes binary)
HIDDEN, LR, EPOCHS, BATCH = [16, 16], 0.01, 200, 32


def graph(seed):
    a = os.path.join(ROOT, "assets/insects")
    nodes = {
        "train": {"type": "table_load", "params": {"path": os.path.join(a, "insects-training.txt")}},
        "test": {"type": "table_load", "params": {"path": os.path.join(a, "insects-testing.txt")}},
        "mlp": {"type": "classifier_train",
                "params": {"hidden": HIDDEN, "activation": "relu", "optimizer": "adam",
                           "learning_rate": LR, "epochs": EPOCHS, "batch_size": BATCH,
                           "seed": seed, "standardize": True},
                "inputs": {"train": "train.table"}},
        "pred": {"type": "classifier_predict",
                 "inputs": {"model": "mlp.model", "data": "test.table"}},
        "wl": {"type": "table_write", "params": {"path": "log.json"}, "inputs": {"value": "mlp.log"}},
        "wp": {"type": "table_write", "params": {"path": "pred.csv"}, "inputs": {"value": "pred.labels"}},
    }
    return {"format": "cgnodes-graph", "version": 1, "nodes": nodes}


def main():
    _images.ensure(["numpy", "sklearn"], ["numpy", "scikit-learn"], __file__, "INSECTS_SKLEARN_REEXEC")
    import warnings

    import numpy as np
    import sklearn
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.neural_network import MLPClassifier

    # 200 epochs is the budget on both sides; sklearn warns that it "has not converged".
    warnings.filterwarnings("ignore", category=ConvergenceWarning)
    from sklearn.preprocessing import StandardScaler

    cg = sys.argv[1] if len(sys.argv) > 1 else _images.cgnodes_bin()
    seeds = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    tr = np.loadtxt(os.path.join(ROOT, "assets/insects/insects-training.txt"))
    te = np.loadtxt(os.path.join(ROOT, "assets/insects/insects-testing.txt"))
    parts = {"first60": slice(0, 60), "other150": slice(60, 210), "all210": slice(0, 210)}

    def acc(pred):
        return {k: float(np.mean(pred[s] == te[s, 2])) for k, s in parts.items()}

    ours, theirs = [], []
    for seed in range(seeds):
        with tempfile.TemporaryDirectory() as d:
            g = os.path.join(d, "g.json")
            with open(g, "w") as f:
                json.dump(graph(seed), f)
            subprocess.run([cg, "run", g, "--out", d, "--threads", "1"], check=True,
                           capture_output=True)
            with open(os.path.join(d, "log.json")) as f:
                secs = float(json.load(f)["meta"]["train_seconds"])
            pred = np.loadtxt(os.path.join(d, "pred.csv"), delimiter=",", skiprows=1)
        ours.append(dict(acc(pred), seconds=secs))

        sc = StandardScaler().fit(tr[:, :2])
        clf = MLPClassifier(hidden_layer_sizes=tuple(HIDDEN), activation="relu", solver="adam",
                            learning_rate_init=LR, max_iter=EPOCHS, batch_size=BATCH,
                            shuffle=True, random_state=seed, alpha=0.0, tol=0.0,
                            n_iter_no_change=EPOCHS, early_stopping=False)
        t0 = time.perf_counter()
        clf.fit(sc.transform(tr[:, :2]), tr[:, 2].astype(int))
        secs = time.perf_counter() - t0
        theirs.append(dict(acc(clf.predict(sc.transform(te[:, :2]))), seconds=secs))

    mean = lambda rows, k: float(np.mean([r[k] for r in rows]))
    out = {"cgnodes": cg, "sklearn": sklearn.__version__, "seeds": seeds, "ours": ours,
           "sklearn_runs": theirs}
    for k in list(parts) + ["seconds"]:
        out[f"mean_{k}"] = {"ours": mean(ours, k), "sklearn": mean(theirs, k)}
    out["time_ratio_ours_over_sklearn"] = out["mean_seconds"]["ours"] / out["mean_seconds"]["sklearn"]
    out["accuracy_at_least_sklearn"] = out["mean_all210"]["ours"] >= out["mean_all210"]["sklearn"]
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
