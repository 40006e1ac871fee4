"""Residual boosting: trees learned on top of the planner's own ranking (the hand-tuned
reward less the path bias, scaled by a one-parameter choice model), their number chosen by
5-fold cross-validation of the pairwise error (0 trees allowed), against the hand-tuned reward
ranked as the planner picks.

Run from a clone with footfall installed, on a curve measured with
``footfall learning-curve --search-radius 0.03 --out CURVE`` (its stores are read, nothing is
written): ``python residual_boosting.py CURVE 100,200``. Terrain features + pose, LightGBM lambdarank with
the boosted learner's settings (``_planner.py``). A lab script, not part of footfall's
interface.
"""
import sys
from pathlib import Path

import lightgbm
import numpy as np
from _planner import LIGHTGBM, difference, held_out, losses, rows, training
from scipy.optimize import minimize_scalar

from footfall.learning.ranker import grouped_folds, pairwise_error, select_on_path

TREES = (0, 10, 25, 50, 100, 200)
curve, sizes = Path(sys.argv[1]), [int(x) for x in sys.argv[2].split(",")]
H, values = held_out(curve)
base = losses([b for _, b, _ in H], values)


def train(X, y, sizes_, init, rounds):
    data = lightgbm.Dataset(X, y, group=sizes_, init_score=init)
    return lightgbm.train(LIGHTGBM, data, num_boost_round=rounds)


for n in sizes:
    per = []
    for d in range(3):
        TX, TB, TY = [], [], []
        for t in training(curve, d, n):
            X, b, _ = rows(t.hmap, t.state, t.candidates)
            y = np.zeros(len(b))
            y[t.chosen] = 1
            TX.append(X), TB.append(b), TY.append(y)
        s = minimize_scalar(lambda s: -sum((s * b)[y == 1][0] - np.logaddexp.reduce(s * b)
                                           for b, y in zip(TB, TY)),
                            bounds=(1e-3, 100), method="bounded").x  # the base as a choice model
        X, Y, B = np.vstack(TX), np.concatenate(TY), s * np.concatenate(TB)
        sizes_ = np.array([len(b) for b in TB])
        groups = np.repeat(np.arange(n), sizes_)
        errs = []
        for tr_i, _ in grouped_folds(np.arange(n), 5):
            m = np.isin(groups, tr_i)
            bst = train(X[m], Y[m], sizes_[tr_i], B[m], TREES[-1])
            errs.append([pairwise_error(B[~m] + (bst.predict(X[~m], num_iteration=T) if T else 0),
                                        Y[~m], groups[~m]) for T in TREES])
        errs = np.array(errs)
        T = TREES[select_on_path(errs.mean(0), errs.std(0), 5, "min")]
        bst = train(X, Y, sizes_, B, T) if T else None
        L = losses([s * b + (bst.predict(x) if T else 0) for x, b, _ in H], values)
        per.append(L)
        print(f"n={n} draw {d}: s={s:.3f} cv errors {np.round(errs.mean(0), 4).tolist()} -> "
              f"{T} trees; mean {L.mean():.2f} above {np.mean(L > 1):.3f} severe "
              f"{np.mean(L > 10):.3f}", flush=True)
    print(f"n={n}: residual {difference(per, base)}", flush=True)
