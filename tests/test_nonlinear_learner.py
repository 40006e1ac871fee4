"""A non-linear ranking learner in one module: registered, learned, saved, loaded, ranked, scored
densely and walked, with no other file of footfall changed.

The learner is a random-Fourier-feature ranker: each candidate's features,
standardised, are mapped by scikit-learn's ``RBFSampler`` to cos(x W + b)
(an approximation of the RBF kernel), and a logistic regression on pairwise
differences of those maps (paper Eq. 3) gives the weights. Its ranking
function is not linear in the features -- it can prefer a *middling* value
of a feature, which w^T x cannot -- and it keeps its own arrays in the
model file (the standardisation, W, b and the weights), never a pickle.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np
import pytest
from sklearn.base import BaseEstimator
from sklearn.kernel_approximation import RBFSampler
from sklearn.linear_model import LogisticRegression

from footfall.core.errors import FootfallError
from footfall.core.state import nominal_state
from footfall.core.validate import require_float_array
from footfall.data.demonstration import Demonstration
from footfall.features.candidates import reachable_footholds
from footfall.features.config import FeatureConfig
from footfall.features.dense import score_grid
from footfall.features.family import (
    FEATURE_SETS,
    Candidates,
    FeatureFamily,
    register_feature_set,
)
from footfall.features.scorer import FootholdScorer
from footfall.features.terrain_features import TerrainFeatures
from footfall.learning.evaluation import rank_scores
from footfall.learning.function import RankingFunction
from footfall.learning.learner import LEARNERS, Learner, register_learner
from footfall.learning.model import FootholdModel
from footfall.learning.ranker import grouped_folds, pairwise_transform
from footfall.learning.train import TrainingDemo, learn_model
from footfall.sim.episode import WalkConfig, walk
from footfall.terrain import make_board


# ------------------------------------------------------------------ the learner
def _features(X: np.ndarray, mean: np.ndarray, scale: np.ndarray, projection: np.ndarray,
              offset: np.ndarray) -> np.ndarray:
    """Random Fourier features (n, D) of raw features X (n, d): RBFSampler's map, from arrays."""
    z = ((X - mean) / scale) @ projection + offset
    return np.cos(z) * np.sqrt(2.0 / projection.shape[1])


class FourierRanker(BaseEstimator):
    """Pairwise logistic regression on random Fourier features of the candidates."""

    def __init__(self, n_components: int = 300, gamma: float = 0.1, C: float = 1.0,
                 cv: int = 3, random_state: int = 0):
        self.n_components = n_components
        self.gamma = gamma
        self.C = C
        self.cv = cv
        self.random_state = random_state

    def _weights(self, phi: np.ndarray, y: np.ndarray, groups: np.ndarray) -> np.ndarray:
        pairs, labels, _ = pairwise_transform(phi, y, groups)
        fit = LogisticRegression(C=self.C, fit_intercept=False, max_iter=2000).fit(pairs, labels)
        return fit.coef_.ravel()

    def fit(self, X: np.ndarray, y: np.ndarray, groups: np.ndarray) -> FourierRanker:
        self.mean_ = X.mean(axis=0)
        scale = X.std(axis=0)
        self.scale_ = np.where(scale > 1e-12, scale, 1.0)
        sampler = RBFSampler(gamma=self.gamma, n_components=self.n_components,
                             random_state=self.random_state).fit((X - self.mean_) / self.scale_)
        self.projection_, self.offset_ = sampler.random_weights_, sampler.random_offset_
        phi = self.transform(X)
        pairs, labels, pair_groups = pairwise_transform(phi, y, groups)
        errors = []
        for train, test in grouped_folds(pair_groups, self.cv):  # held-out demonstrations
            w = LogisticRegression(C=self.C, fit_intercept=False, max_iter=2000).fit(
                pairs[train], labels[train]).coef_.ravel()
            errors.append(np.mean(labels[test] * (pairs[test] @ w) <= 0))
        self.cv_error_ = float(np.mean(errors))
        self.coef_ = self._weights(phi, y, groups)
        return self

    def transform(self, X: np.ndarray) -> np.ndarray:
        return _features(X, self.mean_, self.scale_, self.projection_, self.offset_)

    def decision_function(self, X: np.ndarray) -> np.ndarray:
        return self.transform(X) @ self.coef_


@dataclass(frozen=True, eq=False)
class FourierScorer(FootholdScorer):
    """The function's value of a foothold: w . phi(x) over the families' columns (terrain only)."""

    function: FourierFunction
    config: FeatureConfig = field(default_factory=FeatureConfig)
    name: str = "fourier"

    def family_names(self) -> tuple[str, ...]:
        return tuple(f.name for f in self.function.families)

    def terrain_values(self, c: Candidates) -> np.ndarray:
        X = np.hstack([f.compute(c) for f in self.function.families])
        f = self.function
        value = _features(np.nan_to_num(X), f.mean, f.scale, f.projection, f.offset) @ f.weights
        return np.where(c.patches.valid, value, -np.inf)

    def key(self, state: bool) -> str:
        digest = hashlib.sha256(repr(self.config.to_dict()).encode() + bytes([state]))
        for array in self.function.arrays().values():
            digest.update(np.ascontiguousarray(array).tobytes())
        return digest.hexdigest()


@dataclass(frozen=True, eq=False)
class FourierFunction(RankingFunction):
    families: tuple[FeatureFamily, ...]
    mean: np.ndarray  # (d,) feature means
    scale: np.ndarray  # (d,) feature standard deviations
    projection: np.ndarray  # (d, D) RBFSampler's random weights
    offset: np.ndarray  # (D,) its random offsets [rad]
    weights: np.ndarray  # (D,) the logistic regression's weights
    info: dict = field(default_factory=dict)

    def scorer(self, config: FeatureConfig, name: str) -> FootholdScorer:
        if any(f.needs_state for f in self.families):
            raise FootfallError("this test's learner scores terrain families only")
        return FourierScorer(self, config, name)

    def arrays(self) -> dict[str, np.ndarray]:
        return {"fourier.mean": self.mean, "fourier.scale": self.scale,
                "fourier.projection": self.projection, "fourier.offset": self.offset,
                "fourier.weights": self.weights}

    @classmethod
    def from_arrays(cls, families, arrays, info, prefix=""):
        d = sum(len(f.columns()) for f in families)
        n = np.shape(arrays.get(prefix + "fourier.offset", ()))[0:1]
        D = n[0] if n else 0

        def get(name: str, shape: tuple) -> np.ndarray:
            if prefix + name not in arrays:
                raise FootfallError(f"lacks array {prefix}{name}")
            return require_float_array(arrays[prefix + name], f"array {prefix}{name}", shape,
                                       bound=1e20)

        return cls(tuple(families), get("fourier.mean", (d,)), get("fourier.scale", (d,)),
                   get("fourier.projection", (d, D)), get("fourier.offset", (D,)),
                   get("fourier.weights", (D,)), info)


@dataclass(frozen=True)
class FourierLearner(Learner):
    name: str = "fourier"
    description: str = "pairwise logistic regression on random Fourier features (non-linear)"
    function_type: type = FourierFunction

    def fit(self, X, y, groups, *, Cs=10, cv=5, selection="1se"):
        return FourierRanker(cv=min(int(cv), 3)).fit(X, y, groups)

    def function(self, fitted, families, n_demonstrations):
        return FourierFunction(tuple(families), fitted.mean_, fitted.scale_, fitted.projection_,
                               fitted.offset_, fitted.coef_,
                               {"cv_error": fitted.cv_error_,
                                "n_demonstrations": n_demonstrations})


# ------------------------------------------------------------------ the proof
BOARD = make_board([("flat", 0.0), ("rocky", 0.6), ("flat", 0.0)], seed=2)
MIDDLING = "medium.std"  # the feature whose middling value the demonstrations prefer


@pytest.fixture(scope="module", autouse=True)
def fourier_registered():
    register_learner(FourierLearner())
    register_feature_set("roughness", ("terrain",))  # the terrain features alone, no pose
    yield
    LEARNERS.unregister("fourier")
    FEATURE_SETS.unregister("roughness")


def _demonstrations(n: int = 120) -> list[Demonstration]:
    """Demonstrations on the rocky module whose choice is the candidate whose roughness
    (``medium.std``) is nearest a middling value, the median over all candidates: a preference
    that rises and then falls with the feature, which no w^T x can express."""
    terrain = TerrainFeatures(FeatureConfig())
    column = terrain.columns().index(MIDDLING)
    x0 = BOARD.bounds[0] + 0.70
    sets = []
    for k in range(n):
        leg = ("LF", "RF", "LH", "RH")[k % 4]
        state = nominal_state(BOARD, (x0 + 0.004 * k, -0.08 + 0.04 * (k % 5)), 0.0, leg)
        cand = reachable_footholds(BOARD, state)[::3]
        x = terrain.compute(Candidates.of_state(BOARD, state, cand, terrain.config))[:, column]
        sets.append((state, cand, x))
    middle = np.median(np.concatenate([x for _, _, x in sets]))
    return [Demonstration(BOARD.content_hash(), state, cand, int(np.argmin(np.abs(x - middle))),
                          source="test") for state, cand, x in sets]


@pytest.fixture(scope="module")
def learned(tmp_path_factory):
    demos = _demonstrations()
    training = [TrainingDemo(BOARD, d.state, d.candidates, d.chosen) for d in demos[:96]]
    model = learn_model(training, "roughness", "fourier", cv=3, seed=0, training_candidates=60)
    path = tmp_path_factory.mktemp("fourier") / "fourier.npz"
    model.save(path)
    return model, FootholdModel.load(path), demos


def test_the_learner_is_registered_by_its_own_module():
    assert "fourier" in LEARNERS.names()


def test_a_saved_model_loads_as_the_same_function(learned):
    model, back, demos = learned
    assert back.learner == "fourier"
    assert isinstance(back.functions["front"], FourierFunction)
    d = demos[0]
    c = Candidates.of_state(BOARD, d.state, d.candidates, back.config)
    for leg in ("LF", "RH"):
        np.testing.assert_array_equal(back.reward_for(leg).values(c),
                                      model.reward_for(leg).values(c))


def test_it_ranks_held_out_demonstrations_better_than_a_linear_function(learned):
    _, back, demos = learned
    held_out = demos[96:]
    terrain = {BOARD.content_hash(): BOARD}.__getitem__
    ours = rank_scores(back, held_out, terrain)
    linear = learn_model([TrainingDemo(BOARD, d.state, d.candidates, d.chosen)
                          for d in demos[:96]], "roughness", "l1", cv=3, seed=0,
                         training_candidates=60)
    theirs = rank_scores(linear, held_out, terrain)
    assert ours.n == len(held_out) == 24
    assert ours.percentile > 0.75  # the median roughness ranks near the top
    assert ours.percentile > theirs.percentile  # w^T x cannot prefer a middling value


def test_it_scores_a_board_densely_as_it_scores_candidates(learned):
    _, back, _ = learned
    scorer = back.reward_for("LF")
    grid = score_grid(BOARD, scorer, spacing=0.01)
    rng = np.random.default_rng(0)
    i = rng.integers(0, grid.x.size, 40)
    j = rng.integers(0, grid.y.size, 40)
    xy = np.column_stack([grid.x[i], grid.y[j]])
    footholds = np.column_stack([xy, BOARD.height_at(xy)])
    c = Candidates(BOARD, footholds, 0.0, False, back.config)
    np.testing.assert_allclose(grid.reward[i, j], scorer.terrain_values(c), rtol=1e-12)
    assert grid.valid.mean() > 0.5


def test_it_walks_a_board(learned):
    _, back, _ = learned
    record = walk(BOARD, back.reward_for, 3, WalkConfig(max_steps=6))
    assert len(record.steps) == 6
    assert record.settings["reward"] == ["roughness/fourier/front", "roughness/fourier/hind"]
    for step in record.steps:  # the planner ranked F by the learned function
        assert np.isfinite(step.rewards[step.chosen])
