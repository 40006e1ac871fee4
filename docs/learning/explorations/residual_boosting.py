"""Residual boosting: trees learned on top of the planner's own ranking (the hand-tuned
reward less the path bias, scaled by a one-parameter choice model), their number chosen by
5-fold cross-validation of the pairwise error (0 trees allowed), against the hand-tuned reward.

Run from a clone with footfall installed, on a curve measured with
``footfall learning-curve --search-radius 0.03 --out CURVE`` (its stores are read, nothing is
written): ``python residual_boosting.py CURVE 100,200``. Terrain features + pose, LightGBM lambdarank with
the boosted learner's settings; every figure ranked as the footstep planner picks (path bias
60 hand-tuned reward units per metre from the gait-nominal foothold). A lab script: it reads
the curve module's private helpers and is not part of footfall's interface.
"""
import sys, time, json
from pathlib import Path
import numpy as np
from scipy.optimize import minimize_scalar
import lightgbm
from footfall.experiments.learning_curve import CurveConfig, _held_out, _expert, _draw_training
from footfall.learning.dataset import create_families
from footfall.learning.ranker import pairwise_error, grouped_folds, select_on_path
from footfall.features.config import FeatureConfig
from footfall.features.family import Candidates
from footfall.features.reward import default_reward
from footfall.core.state import stance_target
from footfall.core.robot import LITTLEDOG

out = Path(sys.argv[1]); sizes = [int(x) for x in sys.argv[2].split(",")]
config = CurveConfig(search_radius=0.03); expert = _expert(); fc = FeatureConfig()
fams = create_families("terrain", fc)
hand = default_reward(); lead = expert.config.stance_lead; W = 60.0
TREES = (0, 10, 25, 50, 100, 200)
def rows(hmap, state, cands):
    c = Candidates.of_state(hmap, state, cands, fc, LITTLEDOG)
    X = np.hstack([c.columns(f) for f in fams])
    dist = np.linalg.norm(cands[:, :2] - stance_target(state, LITTLEDOG, lead), axis=1)
    return X, hand.values(c) - W * dist
held = _held_out(out, config, expert, lambda s: None)
HX, HB = zip(*[rows(held.terrain(d.terrain_hash), d.state, d.candidates) for d in held.decisions])
def losses(scores):
    L = []
    for s, v in zip(scores, held.values):
        p = np.flatnonzero(s == s.max()); L.append(v.max() - v[p].mean())
    return np.array(L)
base_losses = losses(HB)
params = dict(objective="lambdarank", num_leaves=7, learning_rate=0.05, min_data_in_leaf=50,
              feature_fraction=0.5, lambda_l2=1.0, seed=0, num_threads=1, deterministic=True,
              verbosity=-1, force_col_wise=True)
def train(X, y, sizes_, init, rounds):
    return lightgbm.train(params, lightgbm.Dataset(X, y, group=sizes_, init_score=init), num_boost_round=rounds)
result = {"base": {"mean": float(base_losses.mean()), "above": float(np.mean(base_losses > 1)), "severe": float(np.mean(base_losses > 10))}}
for n in sizes:
    per = []
    for d in range(3):
        t0 = time.time()
        tr = _draw_training(out, config, d, expert, lambda s: None)[:n]
        TX, TB, TY = [], [], []
        for t in tr:
            X, b = rows(t.hmap, t.state, t.candidates); y = np.zeros(len(b)); y[t.chosen] = 1
            TX.append(X); TB.append(b); TY.append(y)
        s = minimize_scalar(lambda s: -sum((s * b)[y == 1][0] - np.logaddexp.reduce(s * b) for b, y in zip(TB, TY)),
                            bounds=(1e-3, 100), method="bounded").x
        X = np.vstack(TX); Y = np.concatenate(TY); B = s * np.concatenate(TB)
        sizes_ = np.array([len(b) for b in TB]); groups = np.repeat(np.arange(n), sizes_)
        folds = grouped_folds(np.arange(n), 5)
        errs = []
        for tr_i, te_i in folds:
            trm = np.isin(groups, tr_i); tem = ~trm
            bst = train(X[trm], Y[trm], sizes_[tr_i], B[trm], TREES[-1])
            errs.append([pairwise_error(B[tem] + (bst.predict(X[tem], num_iteration=T) if T else 0), Y[tem], groups[tem]) for T in TREES])
        errs = np.array(errs)
        k = select_on_path(errs.mean(0), errs.std(0), 5, "min"); T = TREES[k]
        if T:
            bst = train(X, Y, sizes_, B, T)
            L = losses([s * b + bst.predict(x) for x, b in zip(HX, HB)])
        else:
            L = losses([s * b for b in HB])
        per.append(L)
        print(f"n={n} draw {d}: s={s:.3f} cv errors {np.round(errs.mean(0), 4).tolist()} -> {T} trees; "
              f"mean {L.mean():.2f} above {np.mean(L>1):.3f} severe {np.mean(L>10):.3f} ({time.time()-t0:.0f}s)", flush=True)
    diff = np.concatenate([L - base_losses for L in per])
    rng = np.random.default_rng(0)
    boots = [diff[rng.integers(0, diff.size, diff.size)].mean() for _ in range(2000)]
    print(f"n={n}: residual mean {np.mean([L.mean() for L in per]):.3f} vs hand-tuned {base_losses.mean():.3f}; "
          f"difference {diff.mean():.3f} [{np.percentile(boots, 2.5):.3f}, {np.percentile(boots, 97.5):.3f}]", flush=True)
