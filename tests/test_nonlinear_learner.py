"""The non-linear learners (the kernel ranker and the boosted ranker): learned, saved, loaded,
ranked, scored densely and walked.

Their ranking functions are not linear in the features: they can prefer a
*middling* value of a feature, which w^T x cannot. The demonstrations here
choose the candidate whose roughness is nearest its median; both must rank
held-out demonstrations better than the L1 learner does.
"""

from __future__ import annotations

import numpy as np
import pytest

from footfall.core.state import nominal_state
from footfall.data.demonstration import Demonstration
from footfall.features.candidates import reachable_footholds
from footfall.features.config import FeatureConfig
from footfall.features.dense import score_grid
from footfall.features.family import (
    FEATURE_SETS,
    Candidates,
    register_feature_set,
)
from footfall.features.terrain_features import TerrainFeatures
from footfall.learning.evaluation import rank_scores
from footfall.learning.model import FootholdModel
from footfall.learning.train import TrainingDemo, learn_model
from footfall.sim.episode import WalkConfig, walk
from footfall.terrain import make_board

# ------------------------------------------------------------------ the proof
BOARD = make_board([("flat", 0.0), ("rocky", 0.6), ("flat", 0.0)], seed=2)
MIDDLING = "medium.std"  # the feature whose middling value the demonstrations prefer


NONLINEAR = ("kernel", "lambdarank")


@pytest.fixture(scope="module", autouse=True)
def roughness_registered():
    register_feature_set("roughness", ("terrain",))  # the terrain features alone, no pose
    yield
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
def demonstrations():
    return _demonstrations()


@pytest.fixture(scope="module")
def linear_scores(demonstrations):
    """How the L1 learner ranks the held-out demonstrations."""
    demos = demonstrations
    linear = learn_model([TrainingDemo(BOARD, d.state, d.candidates, d.chosen)
                          for d in demos[:96]], "roughness", "l1", cv=3, seed=0,
                         training_candidates=60)
    return rank_scores(linear, demos[96:], {BOARD.content_hash(): BOARD}.__getitem__)


@pytest.fixture(scope="module", params=NONLINEAR)
def learned(request, demonstrations, tmp_path_factory):
    demos = demonstrations
    training = [TrainingDemo(BOARD, d.state, d.candidates, d.chosen) for d in demos[:96]]
    model = learn_model(training, "roughness", request.param, cv=3, seed=0,
                        training_candidates=60)
    path = tmp_path_factory.mktemp(request.param) / "model.npz"
    model.save(path)
    return model, FootholdModel.load(path), demos


def test_a_saved_model_loads_as_the_same_function(learned):
    model, back, demos = learned
    assert back.learner == model.learner
    assert type(back.functions["front"]) is type(model.functions["front"])
    d = demos[0]
    c = Candidates.of_state(BOARD, d.state, d.candidates, back.config)
    for leg in ("LF", "RH"):
        np.testing.assert_array_equal(back.reward_for(leg).values(c),
                                      model.reward_for(leg).values(c))


def test_it_ranks_held_out_demonstrations_better_than_a_linear_function(learned,
                                                                         linear_scores):
    _, back, demos = learned
    held_out = demos[96:]
    ours = rank_scores(back, held_out, {BOARD.content_hash(): BOARD}.__getitem__)
    theirs = linear_scores
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
    model, back, _ = learned
    record = walk(BOARD, back.reward_for, 3, WalkConfig(max_steps=6))
    assert len(record.steps) == 6
    assert record.settings["reward"] == [f"roughness/{model.learner}/front",
                                         f"roughness/{model.learner}/hind"]
    for step in record.steps:  # the planner ranked F by the learned function
        assert np.isfinite(step.rewards[step.chosen])


def test_the_kernel_clips_a_column_far_outside_its_training_range():
    """A template matched far better than by any training candidate lies hundreds of standard
    deviations out; beyond CLIP it counts as at CLIP, not as a random phase of the cosines."""
    from footfall.learning.kernel import CLIP, fourier_features

    rng = np.random.default_rng(0)
    mean, scale = np.zeros(4), np.ones(4)
    projection, offset = rng.normal(size=(4, 50)), rng.uniform(0, 2 * np.pi, 50)
    at_clip = np.array([[CLIP, 0.0, 0.0, 0.0]])
    far = np.array([[371.0, 0.0, 0.0, 0.0]])
    np.testing.assert_array_equal(fourier_features(far, mean, scale, projection, offset),
                                  fourier_features(at_clip, mean, scale, projection, offset))
    inside = np.array([[CLIP / 2, 0.0, 0.0, 0.0]])
    assert not np.allclose(fourier_features(inside, mean, scale, projection, offset),
                           fourier_features(at_clip, mean, scale, projection, offset))
