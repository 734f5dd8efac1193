#!/usr/bin/python3
"""Fits the confidence model of src/pose/confidence.cpp: the probability that a verified pose is right.

Input: JSON lines written by `viewpose bop --keep-best --hypotheses FILE` (one per pose that passed
verification's bounds, with the features of pose/confidence.hpp and its ADD-S to the nearest
ground truth of its object as a share of the diameter). A pose is right when that share is below
0.1 (the ADD-S threshold `viewpose eval` uses). The model is a logistic regression with a little L2
(on standardized features), fit by Newton's method; it is written out in raw-feature form to paste
into confidence.cpp. Also reported: how well each training file is predicted when it is left out,
the threshold that keeps 98 % precision on the training data, and, for the --check files (real
frames, not fit on), precision and recall at that threshold. A calibration plot goes to --plot.

Usage: scripts/fit-confidence.py --train A.jsonl B.jsonl ... [--check REAL.jsonl ...] [--json OUT] [--plot PNG]
"""
import argparse
import json
import math
from pathlib import Path

import numpy as np

RIGHT_BELOW = 0.1  # ADD-S as a share of the diameter


def load(path):
    rows = [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]
    if not rows:
        return [], np.zeros((0, 0)), np.zeros(0)
    names = list(rows[0]["features"])  # in the order of confidence_features() (bop writes them so)
    X = np.array([[r["features"][n] for n in names] for r in rows], dtype=float)
    y = np.array([1.0 if r["add_s_rel"] is not None and r["add_s_rel"] < RIGHT_BELOW else 0.0 for r in rows])
    return names, X, y


def fit(X, y, l2=1.0, iterations=50):
    """Logistic regression on standardized features; returns (bias, weights) for the raw features."""
    mu, sd = X.mean(0), X.std(0)
    sd[sd < 1e-9] = 1.0
    Z = np.hstack([np.ones((len(X), 1)), (X - mu) / sd])
    w = np.zeros(Z.shape[1])
    reg = l2 * np.eye(len(w))
    reg[0, 0] = 0.0  # the bias is not shrunk
    for _ in range(iterations):
        p = 1.0 / (1.0 + np.exp(-Z @ w))
        gradient = Z.T @ (p - y) + reg @ w
        hessian = Z.T @ (Z * (p * (1 - p))[:, None]) + reg
        step = np.linalg.solve(hessian, gradient)
        w -= step
        if np.abs(step).max() < 1e-10:
            break
    weights = w[1:] / sd
    bias = w[0] - float(weights @ mu)
    return bias, weights


def probability(bias, weights, X):
    return 1.0 / (1.0 + np.exp(-(bias + X @ weights)))


def threshold_for_precision(p, y, precision):
    """The lowest threshold at which everything kept is at least `precision` right (over all cuts at
    or above it, so that the precision does not dip again higher up)."""
    order = np.argsort(-p)
    ps, ys = p[order], y[order]
    kept_right = np.cumsum(ys)
    kept = np.arange(1, len(ys) + 1)
    prec = kept_right / kept
    best = 1.0
    ok = True
    for k in range(len(ps)):
        if k + 1 < len(ps) and ps[k + 1] == ps[k]:
            continue
        ok = ok and prec[k] >= precision
        if ok:
            best = ps[k]
    return float(best)


def summary(p, y, th):
    keep = p >= th
    right = int((keep & (y == 1)).sum())
    wrong = int((keep & (y == 0)).sum())
    return {"hypotheses": int(len(y)), "right": int(y.sum()), "kept_right": right, "kept_wrong": wrong,
            "precision": right / max(right + wrong, 1), "recall_of_right_poses": right / max(int(y.sum()), 1)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--train", nargs="+", required=True)
    ap.add_argument("--check", nargs="*", default=[])
    ap.add_argument("--precision", type=float, default=0.98)
    ap.add_argument("--l2", type=float, default=1.0)
    ap.add_argument("--json")
    ap.add_argument("--plot")
    a = ap.parse_args()

    sets = {Path(f).name: load(f) for f in a.train}
    names = next(s[0] for s in sets.values() if s[0])
    X = np.vstack([s[1] for s in sets.values() if len(s[2])])
    y = np.concatenate([s[2] for s in sets.values() if len(s[2])])
    bias, weights = fit(X, y, a.l2)
    p = probability(bias, weights, X)
    th = threshold_for_precision(p, y, a.precision)
    out = {"features": names, "bias": bias, "weights": list(map(float, weights)), "threshold": th,
           "precision_asked": a.precision, "train": {}, "left_out": {}, "check": {}}
    print(f"{len(y)} hypotheses, {int(y.sum())} right; threshold for {100 * a.precision:.0f} % precision: {th:.3f}")
    for name, (_, Xs, ys) in sets.items():
        if not len(ys):
            continue
        out["train"][name] = summary(probability(bias, weights, Xs), ys, th)
        rest = [s for n, s in sets.items() if n != name and len(s[2])]
        if rest:
            b2, w2 = fit(np.vstack([s[1] for s in rest]), np.concatenate([s[2] for s in rest]), a.l2)
            out["left_out"][name] = summary(probability(b2, w2, Xs), ys, th)
        print(f"  {name}: fit {out['train'][name]}\n  {' ' * len(name)}  left out {out['left_out'].get(name)}")
    for f in a.check:
        _, Xc, yc = load(f)
        if len(yc):
            out["check"][Path(f).name] = summary(probability(bias, weights, Xc), yc, th)
            print(f"  check {Path(f).name}: {out['check'][Path(f).name]}")
    print("\nConfidenceModel for src/pose/confidence.cpp:")
    print(f"  {{{bias:.6g}, {{{', '.join(f'{x:.6g}' for x in weights)}}}}}  // {', '.join(names)}")
    if a.json:
        Path(a.json).write_text(json.dumps(out, indent=1) + "\n")
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(5, 4), dpi=100)
        edges = np.linspace(0, 1, 11)
        for label, (pp, yy) in [("training (simulated)", (p, y))] + [
                (f"check: {Path(f).name}", (probability(bias, weights, load(f)[1]), load(f)[2])) for f in a.check if len(load(f)[2])]:
            mids, rates = [], []
            for lo, hi in zip(edges[:-1], edges[1:]):
                sel = (pp >= lo) & (pp < hi if hi < 1 else pp <= hi)
                if sel.sum() >= 5:
                    mids.append(pp[sel].mean())
                    rates.append(yy[sel].mean())
            ax.plot(mids, rates, "o-", label=label)
        ax.plot([0, 1], [0, 1], "k--", lw=0.8, label="calibrated")
        ax.set_xlabel("confidence (predicted probability right)")
        ax.set_ylabel("share of poses right")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
        ax.set_title("Confidence calibration")
        fig.tight_layout()
        fig.savefig(a.plot)


if __name__ == "__main__":
    main()
