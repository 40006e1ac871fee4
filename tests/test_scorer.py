"""The scorer interface: every reward is a FootholdScorer, and the planners need nothing more."""

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.core.state import nominal_state
from footfall.expert.scorer import ExpertScorer
from footfall.expert.synthetic import SyntheticExpert
from footfall.features.candidates import reachable_footholds
from footfall.features.config import FeatureConfig
from footfall.features.dense import score_grid
from footfall.features.family import Candidates
from footfall.features.pose_features import PoseFeatures
from footfall.features.reward import LinearReward, default_reward, weights_from_names
from footfall.features.scorer import SCORERS, FootholdScorer
from footfall.sim.episode import WalkConfig, walk
from footfall.terrain import make_board

BOARD = make_board([("flat", 0.0), ("rocky", 0.5), ("flat", 0.0)], seed=7)


class Lowest(FootholdScorer):
    """docs/architecture.md's toy scorer: prefers low footholds, terrain part only."""

    name = "lowest"
    config = FeatureConfig()

    def family_names(self):
        return ()

    def terrain_values(self, c):
        return np.where(c.patches.valid, -c.footholds[:, 2], -np.inf)


def _candidates(leg: str = "LF") -> Candidates:
    state = nominal_state(BOARD, (BOARD.bounds[0] + 0.9, 0.0), 0.0, leg)
    return Candidates.of_state(BOARD, state, reachable_footholds(BOARD, state)[::5],
                               FeatureConfig())


def test_a_scorers_value_is_its_terrain_part_plus_its_state_part():
    reward = default_reward()
    posed = reward.with_weights(PoseFeatures(), weights_from_names(
        {"progress": 5.0}, PoseFeatures().columns()))
    c = _candidates()
    assert isinstance(posed, FootholdScorer) and posed.has_state_part
    np.testing.assert_array_equal(posed.values(c),
                                  posed.terrain_values(c) + posed.state_values(c))
    assert not np.array_equal(posed.values(c), reward.values(c))
    np.testing.assert_array_equal(reward.values(c), reward.terrain_values(c))
    assert posed.family_names() == ("templates", "terrain", "pose")


def test_the_expert_as_a_scorer_values_f_as_the_expert_does():
    expert = SyntheticExpert()
    scorer = ExpertScorer(expert)
    c = _candidates("RH")
    usable = np.isfinite(default_reward().terrain_values(c))
    np.testing.assert_array_equal(scorer.terrain_values(c), np.where(usable, 0.0, -np.inf))
    np.testing.assert_array_equal(scorer.state_values(c),
                                  expert.values(BOARD, c.state, c.footholds))
    grid = score_grid(BOARD, scorer, spacing=0.01)
    reference = score_grid(BOARD, default_reward(), spacing=0.01)
    np.testing.assert_array_equal(np.isfinite(grid.reward), np.isfinite(reference.reward))
    assert set(np.unique(grid.reward[np.isfinite(grid.reward)])) == {0.0}
    assert scorer.key(state=False) != default_reward().key(state=False)
    with pytest.raises(FootfallError, match="for a robot state"):
        scorer.state_values(Candidates(BOARD, c.footholds, 0.0, False, FeatureConfig()))


def test_a_scorer_of_its_own_plugs_into_dense_scoring_and_walking():
    scorer = Lowest()
    grid = score_grid(BOARD, scorer, spacing=0.01)
    ok = np.isfinite(grid.reward)
    xy = grid.positions.reshape(grid.reward.shape + (2,))[ok]
    np.testing.assert_allclose(grid.reward[ok], -BOARD.height_at(xy), rtol=0, atol=1e-12)  # (map
    # cells there; interpolation at a cell centre is exact to the last bits)
    record = walk(BOARD, lambda leg: scorer, 0, WalkConfig(max_steps=4))
    assert len(record.steps) == 4 and record.settings["reward"] == ["lowest"]


def test_the_planners_refuse_what_is_not_a_scorer():
    with pytest.raises(FootfallError, match="must return a FootholdScorer"):
        walk(BOARD, lambda leg: "a weight vector", 0, WalkConfig(max_steps=1))


def test_the_hand_tuned_reward_is_a_registered_scorer():
    assert "hand-tuned" in SCORERS.names()
    made = SCORERS.get("hand-tuned")(None)
    assert isinstance(made, LinearReward)
    assert made.key(state=False) == default_reward().key(state=False)
    with pytest.raises(FootfallError, match="unknown scorer 'nope'"):
        SCORERS.get("nope")
