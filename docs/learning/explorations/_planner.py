"""What the exploration scripts share: a planner's-F learning curve's held-out decisions and
training draws as design matrices (terrain features + pose), the hand-tuned reward as the
footstep planner ranks it (less the path bias), and the rule's measure (mean expert shortfall,
paired bootstrap of the difference). A lab module: it reads the curve module's private helpers."""

from pathlib import Path

import numpy as np

from footfall.core.robot import LITTLEDOG
from footfall.core.state import stance_target
from footfall.experiments.learning_curve import CurveConfig, _draw_training, _expert, _held_out
from footfall.features.config import FeatureConfig
from footfall.features.family import Candidates
from footfall.features.reward import default_reward
from footfall.learning.dataset import create_families

CONFIG = CurveConfig(search_radius=0.03)  # the planner's-F curve the scripts read
EXPERT = _expert()
FEATURES = FeatureConfig()
FAMILIES = create_families("terrain", FEATURES)  # terrain features + pose
HAND = default_reward()
LEAD = EXPERT.config.stance_lead  # [m] the gait-nominal foothold's lead
BIAS = 60.0  # [hand-tuned reward/m] the reproduction walk's path bias
LIGHTGBM = dict(objective="lambdarank", num_leaves=7, learning_rate=0.05, min_data_in_leaf=50,
                feature_fraction=0.5, lambda_l2=1.0, seed=0, num_threads=1, deterministic=True,
                verbosity=-1, force_col_wise=True)  # the boosted learner's settings


def rows(hmap, state, cands):
    """Design matrix (n, d), the hand-tuned reward less the path bias (n,) and each
    candidate's distance from the gait-nominal foothold (n,) [m]."""
    c = Candidates.of_state(hmap, state, cands, FEATURES, LITTLEDOG)
    X = np.hstack([c.columns(f) for f in FAMILIES])
    dist = np.linalg.norm(cands[:, :2] - stance_target(state, LITTLEDOG, LEAD), axis=1)
    return X, HAND.values(c) - BIAS * dist, dist


def held_out(curve: Path):
    """The held-out decisions' rows (X, base, dist) and the expert's values of them."""
    held = _held_out(curve, CONFIG, EXPERT, lambda s: None)
    return ([rows(held.terrain(d.terrain_hash), d.state, d.candidates) for d in held.decisions],
            held.values)


def training(curve: Path, draw: int, n: int):
    """The first n demonstrations of a draw, in the curve's order."""
    return _draw_training(curve, CONFIG, draw, EXPERT, lambda s: None)[:n]


def losses(scores, values) -> np.ndarray:
    """The expert's shortfall of each pick (the mean over a scorer's tied best)."""
    return np.array([v.max() - v[np.flatnonzero(s == s.max())].mean()
                     for s, v in zip(scores, values)])


def difference(per_draw, base) -> str:
    """Pooled mean shortfall against ``base``'s, with the 95 % paired bootstrap interval of the
    difference over the draw-decisions."""
    diff = np.concatenate([L - base for L in per_draw])
    rng = np.random.default_rng(0)
    boots = [diff[rng.integers(0, diff.size, diff.size)].mean() for _ in range(2000)]
    return (f"mean {np.mean([L.mean() for L in per_draw]):.3f} vs hand-tuned {base.mean():.3f}; "
            f"difference {diff.mean():.3f} [{np.percentile(boots, 2.5):.3f}, "
            f"{np.percentile(boots, 97.5):.3f}]")
