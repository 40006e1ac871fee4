"""One suite of checks over every registered feature family (footfall.features.family).

A family is tested the moment it registers: its names are unique, its dense
scores equal its per-candidate scores, a right leg on the mirrored terrain
sees what a left leg sees, its parameters round-trip, column selection keeps
the columns it says. ``RimFeatures`` below is a family of the test's own,
registered here without touching any other module, and learned and scored
end to end.
"""

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
import pytest

from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.core.state import RobotState, nominal_state
from footfall.features.candidates import reachable_footholds
from footfall.features.config import FeatureConfig
from footfall.features.dense import score_grid
from footfall.features.family import (
    Candidates,
    FeatureFamily,
    families,
    family_class,
    feature_set_families,
    register_family,
    unregister_family,
)
from footfall.features.reward import LinearReward
from footfall.learning.model import FootholdModel
from footfall.learning.train import TrainingDemo, learn_model
from maps import rough_map

CONFIG = FeatureConfig()
FIT_OPTIONS = {"library_size": 30, "bandwidth_rms": (0.004, 0.004, 0.008)}  # templates' options


@dataclass(frozen=True, eq=False)
class RimFeatures(FeatureFamily):
    """A family of the test's own: the highest point of each scale's patch above the foothold.

    One column per scale [m]; not linear in the patch heights, so the dense
    scorer evaluates :meth:`compute` on every lattice point.
    """

    name: ClassVar[str] = "rim"
    config: FeatureConfig = field(default_factory=FeatureConfig)

    @classmethod
    def create(cls, config: FeatureConfig, robot: RobotDescription = LITTLEDOG) -> "RimFeatures":
        return cls(config)

    def columns(self) -> tuple[str, ...]:
        return tuple(f"{s}.rim" for s in self.config.scale_names)

    def compute(self, c: Candidates) -> np.ndarray:
        rel = c.patches.relative
        out = np.zeros((c.n, len(rel)))
        for s, p in enumerate(rel):  # three scales, each vectorised over the candidates
            has = np.isfinite(p).any(axis=1)
            out[has, s] = np.nanmax(p[has], axis=1)
        return out


@pytest.fixture(scope="module", autouse=True)
def rim_registered():
    register_family(RimFeatures)
    yield
    unregister_family("rim")


CLASSES = {**families(), RimFeatures.name: RimFeatures}  # the built-in families and the test's
NAMES = tuple(CLASSES)


def test_the_suite_covers_every_registered_family():
    assert set(families()) == set(NAMES) >= {"terrain", "templates", "pose", "rim"}


HMAP = rough_map()
STATES = [nominal_state(HMAP, (0.0, 0.0), yaw, leg) for yaw, leg in
          ((0.0, "LF"), (0.1, "RF"), (-0.05, "LH"), (0.0, "RH"))]
CANDIDATES = [reachable_footholds(HMAP, s)[::5] for s in STATES]


def _fitted(name: str) -> FeatureFamily:
    """The family fitted to four demonstrations on the rough map (choices by lowest height)."""
    chosen = [int(np.argmin(c[:, 2])) for c in CANDIDATES]
    return family_class(name).create(CONFIG).fit(
        [HMAP] * len(STATES), STATES, CANDIDATES, chosen, np.random.default_rng(0),
        **FIT_OPTIONS)


def _candidates(family: FeatureFamily, k: int = 0) -> Candidates:
    return Candidates.of_state(HMAP, STATES[k], CANDIDATES[k], CONFIG)


@pytest.mark.parametrize("name", NAMES)
def test_columns_are_named_uniquely_and_computed_for_every_candidate(name):
    family = _fitted(name)
    columns = family.columns()
    assert columns and all(isinstance(c, str) and c for c in columns)
    assert len(set(columns)) == len(columns)
    x = family.compute(_candidates(family))
    assert x.shape == (CANDIDATES[0].shape[0], len(columns))
    assert np.isfinite(x).all()
    # What training keeps gives the same features (templates keep squared distances).
    np.testing.assert_allclose(family.from_prepared(family.prepare(_candidates(family))), x,
                               rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("name", [n for n, cls in CLASSES.items() if not cls.needs_state])
def test_dense_scores_equal_per_candidate_scores(name):
    family = _fitted(name)
    rng = np.random.default_rng(1)
    reward = LinearReward((family,), (rng.normal(size=len(family.columns())),), CONFIG)
    for yaw, mirror in ((0.0, False), (0.0, True), (np.pi, False)):
        grid = score_grid(HMAP, reward, spacing=0.01, yaw=yaw, mirror=mirror, dtype=np.float64)
        points = grid.positions
        footholds = np.column_stack([points, HMAP.height_at(points)])
        direct = reward.terrain_values(Candidates(HMAP, footholds, yaw, mirror, CONFIG))
        dense = np.asarray(grid.reward).ravel()
        np.testing.assert_array_equal(np.isfinite(dense), np.isfinite(direct))
        ok = np.isfinite(direct)
        assert ok.sum() > 100
        np.testing.assert_allclose(dense[ok], direct[ok], rtol=1e-7, atol=1e-9)


@pytest.mark.parametrize("name", NAMES)
def test_a_right_leg_on_the_mirrored_terrain_sees_what_a_left_leg_sees(name):
    family = _fitted(name)
    flip = np.array([1.0, -1.0, 1.0])
    swap = [1, 0, 3, 2]  # LF <-> RF, LH <-> RH
    left = STATES[0]
    right = RobotState(left.feet[swap] * flip, left.body_position * flip,
                       left.body_rpy * np.array([-1.0, 1.0, -1.0]), "RF", left.goal * flip[:2])
    mirrored = HMAP.mirrored_y()
    a = family.compute(Candidates.of_state(HMAP, left, CANDIDATES[0], CONFIG))
    b = family.compute(Candidates.of_state(mirrored, right, CANDIDATES[0] * flip, CONFIG))
    np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("name", NAMES)
def test_parameters_round_trip_and_digest(name):
    family = _fitted(name)
    arrays, meta = family.params()
    back = type(family).from_params(CONFIG, LITTLEDOG, arrays, meta)
    assert back.columns() == family.columns()
    assert back.digest() == family.digest()
    c = _candidates(family, 1)
    np.testing.assert_array_equal(back.compute(c), family.compute(c))


@pytest.mark.parametrize("name", NAMES)
def test_selection_keeps_exactly_the_columns_it_reports(name):
    family = _fitted(name)
    n = len(family.columns())
    nonzero = np.arange(n) % 3 == 0
    reduced, keep = family.select(nonzero)
    assert keep.shape == (n,) and keep.dtype == bool
    assert keep[nonzero].all()  # a column with weight is never dropped
    assert len(reduced.columns()) == keep.sum()
    c = _candidates(family, 2)
    np.testing.assert_allclose(reduced.compute(c), family.compute(c)[:, keep], rtol=1e-12)


def test_a_new_family_is_learned_saved_and_scored_without_touching_the_others(tmp_path):
    """``terrain+rim+pose``: the registered family is learned on, kept in the file, scored."""
    assert feature_set_families("terrain+rim+pose") == ("terrain", "rim", "pose")
    board = rough_map(seed=9)
    demos = []
    for k, (x, leg) in enumerate([(x, leg) for x in (-0.05, 0.0, 0.05)
                                  for leg in ("LF", "RF", "LH", "RH")]):
        state = nominal_state(board, (x, 0.01 * (k % 3 - 1)), 0.0, leg)
        cand = reachable_footholds(board, state)[::3]
        rim = RimFeatures(CONFIG).compute(Candidates.of_state(board, state, cand, CONFIG))
        demos.append(TrainingDemo(board, state, cand, int(np.argmin(rim[:, 1]))))  # no rim
    model = learn_model(demos, "terrain+rim+pose", cv=3, Cs=5, training_candidates=40)
    for group in ("front", "hind"):
        f = model.functions[group]
        assert [fam.name for fam in f.families] == ["terrain", "rim", "pose"]
        assert f.weights("rim")[1] < 0  # the choices avoid a medium-scale rim
    path = tmp_path / "rim.npz"
    model.save(path)
    back = FootholdModel.load(path)
    state = nominal_state(board, (0.02, 0.0), 0.0, "LF")
    cand = reachable_footholds(board, state)
    c = Candidates.of_state(board, state, cand, CONFIG)
    np.testing.assert_array_equal(back.reward_for("LF").terrain_values(c),
                                  model.reward_for("LF").terrain_values(c))
    grid = score_grid(board, back.reward_for("LF"), spacing=0.01, dtype=np.float64)
    assert np.isfinite(np.asarray(grid.reward)).sum() > 100


def test_another_state_shares_the_patches_and_terrain_columns_not_the_pose_ones():
    """A planner's rollouts value the same footholds from several states: with_state computes the
    patches and the terrain families' columns once, and each state's pose features its own --
    every column equal to the one a fresh candidate set of that state computes."""
    board = rough_map(seed=4)
    first = nominal_state(board, (0.0, 0.0), 0.0, "LF")
    moved = nominal_state(board, (0.015, 0.004), 0.0, "LF")  # the body elsewhere, same heading
    f = reachable_footholds(board, first)[::7]
    terrain, pose = (family_class(n).create(CONFIG, LITTLEDOG) for n in ("terrain", "pose"))
    a = Candidates.of_state(board, first, f, CONFIG)
    early = a.with_state(moved)  # before anything read the patches: none are made yet
    assert "patches" not in a.__dict__ and "patches" not in early.__dict__
    assert early.patches is a.patches  # made once, when the later set first reads them
    b = a.with_state(moved)
    again = b.with_state(first)  # a set made from a made one shares the first's too
    fresh = Candidates.of_state(board, moved, f, CONFIG)
    assert b.patches is a.patches and again.patches is a.patches and b.state is moved
    assert b.columns(terrain) is a.columns(terrain)  # one matrix for both states
    np.testing.assert_array_equal(b.columns(terrain), fresh.columns(terrain))
    np.testing.assert_array_equal(b.columns(pose), fresh.columns(pose))
    assert not np.array_equal(b.columns(pose), a.columns(pose), equal_nan=True)
    for other in (nominal_state(board, (0.0, 0.0), 0.3, "LF"),  # another heading
                  nominal_state(board, (0.0, 0.0), 0.0, "RF")):  # a mirrored leg
        with pytest.raises(ValueError, match="with_state"):
            a.with_state(other)
