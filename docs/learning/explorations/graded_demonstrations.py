"""Graded demonstrations: the expert's verdict of every candidate of a demonstration as the
relevance of a lambdarank (the chosen foothold 3, within the margin of the expert's best 2,
short of it by at most the severe threshold 1, severe 0), the trees by 5-fold cross-validated
pairwise error of the chosen foothold, against the hand-tuned reward ranked as the planner
picks. The learned function is measured alone, and with the path bias scaled by the ratio of
its values' spread to the hand-tuned reward's over the held-out candidates (the planner's rule
scales by the spread over a reference module).

Run from a clone with footfall installed, on a curve measured with
``footfall learning-curve --search-radius 0.03 --out CURVE`` (its stores are read, nothing is
written): ``python graded_demonstrations.py CURVE 100,200``. Terrain features + pose, LightGBM lambdarank with
the boosted learner's settings (``_planner.py``). A lab script, not part of footfall's
interface.
"""
import sys
from pathlib import Path

import lightgbm
import numpy as np
from _planner import BIAS, EXPERT, LIGHTGBM, difference, held_out, losses, rows, training

from footfall.learning.ranker import grouped_folds, pairwise_error, select_on_path

TREES = (10, 25, 50, 100, 200, 400)
curve, sizes = Path(sys.argv[1]), [int(x) for x in sys.argv[2].split(",")]
H, values = held_out(curve)
base = losses([b for _, b, _ in H], values)
hand_spread = np.concatenate([b + BIAS * dd for _, b, dd in H]).std()  # the hand-tuned reward's
params = {**LIGHTGBM, "label_gain": [0, 1, 3, 7]}


def train(X, y, sizes_, rounds):
    return lightgbm.train(params, lightgbm.Dataset(X, y, group=sizes_), num_boost_round=rounds)


for n in sizes:
    per, per_b = [], []
    for d in range(3):
        TX, TY, CH = [], [], []
        for t in training(curve, d, n):
            X, _, _ = rows(t.hmap, t.state, t.candidates)
            v = EXPERT.values(t.hmap, t.state, t.candidates)
            short = v.max() - v
            y = np.where(short > 10, 0, np.where(short > 1, 1, 2)).astype(float)
            y[t.chosen] = 3
            TX.append(X), TY.append(y), CH.append(t.chosen)
        X, Y = np.vstack(TX), np.concatenate(TY)
        sizes_ = np.array([len(y) for y in TY])
        groups = np.repeat(np.arange(n), sizes_)
        chosen = np.concatenate([np.arange(len(y)) == c for y, c in zip(TY, CH)]).astype(float)
        errs = []
        for tr_i, _ in grouped_folds(np.arange(n), 5):
            m = np.isin(groups, tr_i)
            bst = train(X[m], Y[m], sizes_[tr_i], TREES[-1])
            errs.append([pairwise_error(bst.predict(X[~m], num_iteration=T), chosen[~m],
                                        groups[~m]) for T in TREES])
        errs = np.array(errs)
        T = TREES[select_on_path(errs.mean(0), errs.std(0), 5, "min")]
        bst = train(X, Y, sizes_, T)
        pred = [bst.predict(x) for x, _, _ in H]
        L = losses(pred, values)  # the learned function alone
        ratio = np.concatenate(pred).std() / hand_spread
        Lb = losses([p - BIAS * ratio * dd for p, (_, _, dd) in zip(pred, H)], values)
        per.append(L), per_b.append(Lb)
        print(f"n={n} draw {d}: {T} trees; alone: mean {L.mean():.2f} above {np.mean(L > 1):.3f} "
              f"severe {np.mean(L > 10):.3f}; with the bias: mean {Lb.mean():.2f} above "
              f"{np.mean(Lb > 1):.3f} severe {np.mean(Lb > 10):.3f}", flush=True)
    print(f"n={n}, alone: graded {difference(per, base)}", flush=True)
    print(f"n={n}, with the bias: graded {difference(per_b, base)}", flush=True)
