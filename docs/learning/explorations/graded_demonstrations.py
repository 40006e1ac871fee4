"""Graded demonstrations: the expert's verdict of every candidate of a demonstration as the
relevance of a lambdarank (the chosen foothold 3, within the margin of the expert's best 2,
short of it by at most the severe threshold 1, severe 0), against the hand-tuned reward.

Run from a clone with footfall installed, on a curve measured with
``footfall learning-curve --search-radius 0.03 --out CURVE`` (its stores are read, nothing is
written): ``python graded_demonstrations.py CURVE 100,200``. Terrain features + pose, LightGBM
lambdarank with the boosted learner's settings, trees by 5-fold cross-validated pairwise error
of the chosen foothold. The hand-tuned reward is ranked as the footstep planner picks (path
bias 60 per metre from the gait-nominal foothold); the learned function alone, and with the
bias scaled by the ratio of its values' spread to the hand-tuned reward's over the held-out
candidates (the planner's rule scales by the spread over a reference module). A lab script: it
reads the curve module's private helpers and is not part of footfall's interface.
"""
import sys, time
from pathlib import Path
import numpy as np
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
TREES = (10, 25, 50, 100, 200, 400)
def rows(hmap, state, cands):
    c = Candidates.of_state(hmap, state, cands, fc, LITTLEDOG)
    X = np.hstack([c.columns(f) for f in fams])
    dist = np.linalg.norm(cands[:, :2] - stance_target(state, LITTLEDOG, lead), axis=1)
    return X, hand.values(c) - W * dist, dist
held = _held_out(out, config, expert, lambda s: None)
H = [rows(held.terrain(d.terrain_hash), d.state, d.candidates) for d in held.decisions]
def losses(scores):
    return np.array([v.max() - v[np.flatnonzero(s == s.max())].mean() for s, v in zip(scores, held.values)])
base = losses([b for _, b, _ in H])
hand_spread = np.concatenate([b + W * dd for _, b, dd in H]).std()  # the hand-tuned reward's own
params = dict(objective="lambdarank", num_leaves=7, learning_rate=0.05, min_data_in_leaf=50,
              feature_fraction=0.5, lambda_l2=1.0, seed=0, num_threads=1, deterministic=True,
              verbosity=-1, force_col_wise=True, label_gain=[0, 1, 3, 7])
def train(X, y, sizes_, rounds):
    return lightgbm.train(params, lightgbm.Dataset(X, y, group=sizes_), num_boost_round=rounds)
print(f"hand-tuned + bias: mean {base.mean():.3f} severe {np.mean(base > 10):.3f}", flush=True)
for n in sizes:
    per, per_b = [], []
    for d in range(3):
        t0 = time.time()
        tr = _draw_training(out, config, d, expert, lambda s: None)[:n]
        TX, TY, CH = [], [], []
        for t in tr:
            X, _, _ = rows(t.hmap, t.state, t.candidates)
            v = expert.values(t.hmap, t.state, t.candidates); short = v.max() - v
            y = np.where(short > 10, 0, np.where(short > 1, 1, 2)).astype(float); y[t.chosen] = 3
            TX.append(X); TY.append(y); CH.append(t.chosen)
        X = np.vstack(TX); Y = np.concatenate(TY); sizes_ = np.array([len(y) for y in TY])
        groups = np.repeat(np.arange(n), sizes_); chosen = np.concatenate([np.arange(len(y)) == c for y, c in zip(TY, CH)]).astype(float)
        errs = []
        for tr_i, te_i in grouped_folds(np.arange(n), 5):
            m = np.isin(groups, tr_i)
            bst = train(X[m], Y[m], sizes_[tr_i], TREES[-1])
            errs.append([pairwise_error(bst.predict(X[~m], num_iteration=T), chosen[~m], groups[~m]) for T in TREES])
        errs = np.array(errs); T = TREES[select_on_path(errs.mean(0), errs.std(0), 5, "min")]
        bst = train(X, Y, sizes_, T)
        pred = [bst.predict(x) for x, _, _ in H]
        L = losses(pred)  # the learned function alone
        ratio = np.concatenate(pred).std() / hand_spread
        Lb = losses([p - W * ratio * dd for p, (_, _, dd) in zip(pred, H)])  # with the path bias
        per.append(L); per_b.append(Lb)
        print(f"n={n} draw {d}: {T} trees; alone: mean {L.mean():.2f} above {np.mean(L>1):.3f} "
              f"severe {np.mean(L>10):.3f}; with the bias: mean {Lb.mean():.2f} above "
              f"{np.mean(Lb>1):.3f} severe {np.mean(Lb>10):.3f} ({time.time()-t0:.0f}s)", flush=True)
    for how, runs in (("alone", per), ("with the bias", per_b)):
        diff = np.concatenate([L - base for L in runs])
        rng = np.random.default_rng(0)
        boots = [diff[rng.integers(0, diff.size, diff.size)].mean() for _ in range(2000)]
        print(f"n={n}, {how}: graded mean {np.mean([L.mean() for L in runs]):.3f} vs hand-tuned "
              f"{base.mean():.3f}; difference {diff.mean():.3f} [{np.percentile(boots, 2.5):.3f}, "
              f"{np.percentile(boots, 97.5):.3f}]", flush=True)
