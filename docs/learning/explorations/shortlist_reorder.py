"""A learned function that only reorders the hand-tuned planner's k best candidates, k chosen
by 5-fold cross-validated top-1 on the demonstrations, against the hand-tuned reward.

Run from a clone with footfall installed, on a curve measured with
``footfall learning-curve --search-radius 0.03 --out CURVE`` (its stores are read, nothing is
written): ``python shortlist_reorder.py CURVE 100,200``. Terrain features + pose, LightGBM lambdarank with
the boosted learner's settings; every figure ranked as the footstep planner picks (path bias
60 hand-tuned reward units per metre from the gait-nominal foothold). A lab script: it reads
the curve module's private helpers and is not part of footfall's interface.
"""
import sys, time
from pathlib import Path
import numpy as np
import lightgbm
from footfall.experiments.learning_curve import CurveConfig, _held_out, _expert, _draw_training
from footfall.learning.dataset import create_families
from footfall.learning.ranker import grouped_folds
from footfall.features.config import FeatureConfig
from footfall.features.family import Candidates
from footfall.features.reward import default_reward
from footfall.core.state import stance_target
from footfall.core.robot import LITTLEDOG

out = Path(sys.argv[1]); sizes = [int(x) for x in sys.argv[2].split(",")]
config = CurveConfig(search_radius=0.03); expert = _expert(); fc = FeatureConfig()
fams = create_families("terrain", fc)
hand = default_reward(); lead = expert.config.stance_lead; W = 60.0
KS = (1, 3, 5, 10, 20, 40, 1000)
TREES = 100
def rows(hmap, state, cands):
    c = Candidates.of_state(hmap, state, cands, fc, LITTLEDOG)
    X = np.hstack([c.columns(f) for f in fams])
    dist = np.linalg.norm(cands[:, :2] - stance_target(state, LITTLEDOG, lead), axis=1)
    return X, hand.values(c) - W * dist
def pick(base, learned, k):
    short = np.argsort(-base, kind="stable")[:k]
    return short[np.argmax(learned[short])]
held = _held_out(out, config, expert, lambda s: None)
HX, HB = zip(*[rows(held.terrain(d.terrain_hash), d.state, d.candidates) for d in held.decisions])
params = dict(objective="lambdarank", num_leaves=7, learning_rate=0.05, min_data_in_leaf=50,
              feature_fraction=0.5, lambda_l2=1.0, seed=0, num_threads=1, deterministic=True,
              verbosity=-1, force_col_wise=True)
def train(TX, TY):
    return lightgbm.train(params, lightgbm.Dataset(np.vstack(TX), np.concatenate(TY), group=[len(y) for y in TY]), num_boost_round=TREES)
base_l = np.array([v.max() - v[np.argmax(b)] for b, v in zip(HB, held.values)])
print(f"hand-tuned + bias: mean {base_l.mean():.3f}", flush=True)
for n in sizes:
    per = []
    for d in range(3):
        tr = _draw_training(out, config, d, expert, lambda s: None)[:n]
        TX, TB, TY, CH = [], [], [], []
        for t in tr:
            X, b = rows(t.hmap, t.state, t.candidates); y = np.zeros(len(b)); y[t.chosen] = 1
            TX.append(X); TB.append(b); TY.append(y); CH.append(t.chosen)
        top1 = np.zeros(len(KS))
        for tr_i, te_i in grouped_folds(np.arange(n), 5):
            bst = train([TX[i] for i in tr_i], [TY[i] for i in tr_i])
            for i in te_i:
                lv = bst.predict(TX[i])
                top1 += [pick(TB[i], lv, k) == CH[i] for k in KS]
        k = KS[int(np.argmax(top1))]
        bst = train(TX, TY)
        L = np.array([v.max() - v[pick(b, bst.predict(x), k)] for x, b, v in zip(HX, HB, held.values)])
        per.append(L)
        print(f"n={n} draw {d}: cv top-1 by k {dict(zip(KS, (top1 / n).round(3)))} -> k={k}; "
              f"mean {L.mean():.2f} above {np.mean(L>1):.3f} severe {np.mean(L>10):.3f}", flush=True)
    diff = np.concatenate([L - base_l for L in per])
    rng = np.random.default_rng(0)
    boots = [diff[rng.integers(0, diff.size, diff.size)].mean() for _ in range(2000)]
    print(f"n={n}: shortlist mean {np.mean([L.mean() for L in per]):.3f} vs hand-tuned {base_l.mean():.3f}; "
          f"difference {diff.mean():.3f} [{np.percentile(boots, 2.5):.3f}, {np.percentile(boots, 97.5):.3f}]", flush=True)
