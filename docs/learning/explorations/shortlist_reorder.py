"""A learned function that only reorders the hand-tuned planner's k best candidates, k chosen
by 5-fold cross-validated top-1 on the demonstrations, against the hand-tuned reward ranked as
the planner picks.

Run from a clone with footfall installed, on a curve measured with
``footfall learning-curve --search-radius 0.03 --out CURVE`` (its stores are read, nothing is
written): ``python shortlist_reorder.py CURVE 100,200``. Terrain features + pose, LightGBM lambdarank with
the boosted learner's settings (``_planner.py``). A lab script, not part of footfall's
interface.
"""
import sys
from pathlib import Path

import lightgbm
import numpy as np
from _planner import LIGHTGBM, difference, held_out, losses, rows, training

from footfall.learning.ranker import grouped_folds

KS = (1, 3, 5, 10, 20, 40, 1000)  # shortlist lengths (1000: no shortlist)
TREES = 100
curve, sizes = Path(sys.argv[1]), [int(x) for x in sys.argv[2].split(",")]
H, values = held_out(curve)
base = losses([b for _, b, _ in H], values)


def pick(b, learned, k):
    short = np.argsort(-b, kind="stable")[:k]
    return short[np.argmax(learned[short])]


def train(TX, TY):
    data = lightgbm.Dataset(np.vstack(TX), np.concatenate(TY), group=[len(y) for y in TY])
    return lightgbm.train(LIGHTGBM, data, num_boost_round=TREES)


for n in sizes:
    per = []
    for d in range(3):
        TX, TB, TY, CH = [], [], [], []
        for t in training(curve, d, n):
            X, b, _ = rows(t.hmap, t.state, t.candidates)
            y = np.zeros(len(b))
            y[t.chosen] = 1
            TX.append(X), TB.append(b), TY.append(y), CH.append(t.chosen)
        top1 = np.zeros(len(KS))
        for tr_i, te_i in grouped_folds(np.arange(n), 5):
            bst = train([TX[i] for i in tr_i], [TY[i] for i in tr_i])
            for i in te_i:
                learned = bst.predict(TX[i])
                top1 += [pick(TB[i], learned, k) == CH[i] for k in KS]
        k = KS[int(np.argmax(top1))]
        bst = train(TX, TY)
        L = np.array([v.max() - v[pick(b, bst.predict(x), k)] for (x, b, _), v in zip(H, values)])
        per.append(L)
        print(f"n={n} draw {d}: cv top-1 by k {dict(zip(KS, (top1 / n).round(3).tolist()))} -> "
              f"k={k}; mean {L.mean():.2f} above {np.mean(L > 1):.3f} severe "
              f"{np.mean(L > 10):.3f}", flush=True)
    print(f"n={n}: shortlist {difference(per, base)}", flush=True)
