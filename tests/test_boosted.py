"""The boosted ranker's trees as checked arrays: LightGBM's predictions exactly, and a bad forest
refused at load with one line naming the array (never handed to a parser that can crash)."""

import gc
import weakref
from dataclasses import replace

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.features.family import Candidates
from footfall.features.templates import BANDWIDTH_RMS_GRID, ORDER_ONLY_RMS
from footfall.learning.boosted import BoostedRanker, Forest
from footfall.learning.model import FootholdModel
from footfall.learning.ranker import pairwise_error
from footfall.learning.train import learn_model
from test_bad_models import read_raw, write_raw
from test_learners import lowest_foothold_demos


def _toy(seed=0, n_demos=60, n=20, d=8):
    """Demonstrations whose choice maximises x0 - x1^2 (a middling x1 is best)."""
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n_demos * n, d))
    score = (X[:, 0] - X[:, 1] ** 2).reshape(n_demos, n)
    y = np.zeros(n_demos * n, dtype=int)
    y[np.arange(n_demos) * n + np.argmax(score, axis=1)] = 1
    return X, y, np.repeat(np.arange(n_demos), n)


@pytest.mark.parametrize("objective", ["lambdarank", "rank_xendcg"])
def test_the_forest_gives_lightgbm_s_own_predictions(objective):
    X, y, groups = _toy()
    ranker = BoostedRanker(objective, trees=(5, 20, 40), cv=3).fit(X, y, groups)
    booster = ranker._train(ranker._dataset(X, y, np.bincount(groups)), ranker.n_trees_)
    rng = np.random.default_rng(1)
    fresh = rng.normal(size=(5000, X.shape[1]))
    np.testing.assert_array_equal(ranker.forest_.predict(fresh), booster.predict(fresh))
    assert ranker.forest_.roots.size == ranker.n_trees_
    assert ranker.n_trees_ in (5, 20, 40) and len(ranker.path_) == 3


def test_demonstrations_in_any_row_order_form_their_own_queries():
    """LightGBM reads a query as contiguous rows: shuffled rows are grouped before training (a
    query mixing demonstrations would learn nothing). Row order changes LightGBM's floating-point
    sums, so the forests are close, not equal."""
    X, y, groups = _toy(2)
    order = np.random.default_rng(0).permutation(X.shape[0])
    b = BoostedRanker(trees=(10, 30), cv=3).fit(X[order], y[order], groups[order])
    assert pairwise_error(b.decision_function(X), y, groups) < 0.1


def test_a_folds_rows_are_not_kept_once_binned():
    """The binned data holds no reference to the rows it was made from: a fold's copy of X
    (over a gigabyte at 1 600 demonstrations) is freed before its trees grow."""
    X, y, groups = _toy(4)
    rows = X[groups < 40].copy()
    kept = weakref.ref(rows)
    data = BoostedRanker()._dataset(rows, y[groups < 40], np.bincount(groups[groups < 40]))
    del rows
    gc.collect()
    assert kept() is None and data.num_data() == 40 * 20


def test_the_trees_do_not_depend_on_the_number_of_threads():
    """One thread by default (threads spin on busy cores); any number grows the same trees."""
    X, y, groups = _toy(3)
    one = BoostedRanker(trees=(10, 40), cv=3).fit(X, y, groups)
    two = BoostedRanker(trees=(10, 40), cv=3, n_jobs=2).fit(X, y, groups)
    assert one.get_params()["n_jobs"] == 1 and one.n_trees_ == two.n_trees_
    for name, array in one.forest_.arrays().items():
        np.testing.assert_array_equal(array, two.forest_.arrays()[name])
    with pytest.raises(FootfallError, match="n_jobs must be at least 1"):
        BoostedRanker(n_jobs=0).fit(X, y, groups)


def test_a_row_s_value_is_its_own():
    """The compiled walk values each row alone: any split of the rows gives the same bits (a
    planner values the rollouts' states in one call)."""
    X, y, groups = _toy(seed=3)
    forest = BoostedRanker("lambdarank", trees=(25,), cv=3).fit(X, y, groups).forest_
    rows = np.random.default_rng(2).normal(size=(300, X.shape[1]))
    whole = forest.predict(rows)
    pieces = np.concatenate([forest.predict(rows[a:b]) for a, b in ((0, 1), (1, 8), (8, 300))])
    np.testing.assert_array_equal(pieces, whole)
    np.testing.assert_array_equal(forest.predict(rows[::-1]), whole[::-1])
    assert forest.predict(rows[:0]).shape == (0,)


def test_the_rollouts_states_valued_at_once_are_valued_as_one_at_a_time(saved):
    """A boosted function with pose features values the same footholds from several states in
    one call (:meth:`state_values_each`) with the numbers of one call per state."""
    model = FootholdModel.load(saved)
    scorer = model.reward_for("LF")
    demo = lowest_foothold_demos()[0]
    first = Candidates.of_state(demo.hmap, demo.state, demo.candidates, scorer.config)
    states = [replace(demo.state, body_position=demo.state.body_position + (dx, 0.0, dz))
              for dx, dz in ((0.0, 0.0), (0.012, 0.004), (-0.01, -0.006))]
    sets = [first] + [first.with_state(s) for s in states[1:]]
    together = scorer.state_values_each(sets)
    alone = np.stack([scorer.state_values(Candidates.of_state(demo.hmap, s, demo.candidates,
                                                              scorer.config)) for s in states])
    np.testing.assert_array_equal(together, alone)
    assert together.shape == (3, demo.candidates.shape[0]) and np.ptp(together, axis=0).any()
    with pytest.raises(FootfallError, match="same size"):
        scorer.state_values_each([first, Candidates.of_state(demo.hmap, demo.state,
                                                             demo.candidates[:5], scorer.config)])


def _stump() -> dict:
    """One tree: a split on column 1 at 0.5, leaves -1 and +2."""
    return {"feature": np.array([1.0, -1, -1]), "threshold": np.array([0.5, 0, 0]),
            "left": np.array([1.0, 1, 2]), "right": np.array([2.0, 1, 2]),
            "value": np.array([0.0, -1, 2]), "roots": np.array([0.0])}


def test_a_stump_splits_as_written():
    forest = Forest.from_arrays(_stump(), 3, "")
    X = np.array([[9.0, 0.5, 9.0], [9.0, 0.51, 9.0]])
    np.testing.assert_array_equal(forest.predict(X), [-1.0, 2.0])  # x <= t goes left
    assert forest.depth == 1


@pytest.mark.parametrize("change, match", [
    (lambda a: a["left"].__setitem__(0, 0.0), "lead from each node to later ones"),
    (lambda a: a["right"].__setitem__(1, 2.0), "lead from each node to later ones"),
    (lambda a: a["feature"].__setitem__(0, 3.0), r"feature must hold whole numbers in \[-1, 2\]"),
    (lambda a: a["left"].__setitem__(0, 1.5), "left must hold whole numbers"),
    (lambda a: a["roots"].__setitem__(0, 7.0), "roots must hold whole numbers"),
    (lambda a: a.__setitem__("value", np.zeros(2)), r"value must have shape \(3,\)"),
    (lambda a: a["threshold"].__setitem__(0, np.nan), "threshold must be finite"),
    (lambda a: a.pop("roots"), "lacks array roots"),
])
def test_a_bad_forest_is_refused_naming_the_array(change, match):
    arrays = _stump()
    change(arrays)
    with pytest.raises(FootfallError, match=match):
        Forest.from_arrays(arrays, 3, "")


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """A boosted model over the terrain features, saved."""
    demos = lowest_foothold_demos()
    model = learn_model(demos, "terrain", "lambdarank", cv=3, training_candidates=30)
    path = tmp_path_factory.mktemp("boosted") / "model.npz"
    model.save(path)
    return path


def test_the_saved_trees_are_named_arrays_of_the_model_file(saved):
    raw, meta = read_raw(saved)
    assert meta["learner"] == "lambdarank"
    assert meta["groups"]["front"]["function"] == [f"boosted.{k}" for k in sorted(
        ("feature", "left", "right", "roots", "threshold", "value"))]
    assert all(raw[f"front.boosted.{k}"].dtype == np.float64 for k in ("feature", "roots"))
    assert FootholdModel.load(saved).functions["front"].info["trees"] >= 1


@pytest.mark.parametrize("key, make, match", [
    ("front.boosted.left", lambda a: np.zeros_like(a), "front.boosted.left"),
    ("hind.boosted.feature", lambda a: a + 1000, "hind.boosted.feature"),
    ("front.boosted.roots", lambda a: a.astype(np.int64), "front.boosted.roots"),
])
def test_a_tampered_model_file_is_refused_in_one_line(saved, tmp_path, key, make, match):
    raw, meta = read_raw(saved)
    raw[key] = make(raw[key])
    path = tmp_path / "bad.npz"
    write_raw(path, raw, meta)
    with pytest.raises(FootfallError, match=match) as err:
        FootholdModel.load(path)
    assert "\n" not in str(err.value)


def test_the_trees_read_only_each_column_s_order():
    """Why no bandwidth is searched for the trees: RBF similarities exp(-h d) at any bandwidth h
    are one decreasing re-map of the distances d, and the trees split on a column's order, so
    every bandwidth grows the same trees and ranks the candidates it learned from the same (a
    threshold is a midpoint between two values, so a new candidate between them may fall either
    side of it at different bandwidths)."""
    rng = np.random.default_rng(6)
    d = rng.gamma(2.0, 1.0, size=(60 * 20, 6))  # squared distances to six templates
    score = (-d[:, 0] + 0.5 * d[:, 1]).reshape(60, 20)
    y = np.zeros(d.shape[0], dtype=int)
    y[np.arange(60) * 20 + np.argmax(score, axis=1)] = 1
    groups = np.repeat(np.arange(60), 20)
    bandwidths = (0.25, 1.0, 4.0)
    fits = [BoostedRanker(trees=(10, 40), cv=3).fit(np.exp(-h * d), y, groups)
            for h in bandwidths]
    first = fits[0].decision_function(np.exp(-bandwidths[0] * d))
    for h, other in zip(bandwidths[1:], fits[1:]):
        assert other.n_trees_ == fits[0].n_trees_ and other.cv_error_ == fits[0].cv_error_
        for name in ("feature", "left", "right", "value", "roots"):  # thresholds in h's units
            np.testing.assert_array_equal(other.forest_.arrays()[name],
                                          fits[0].forest_.arrays()[name])
        np.testing.assert_array_equal(other.decision_function(np.exp(-h * d)), first)


def test_the_trees_bandwidths_are_set_not_searched():
    """For lambdarank the template family's bandwidths come from ORDER_ONLY_RMS on every scale,
    without cross-validating a grid; the L1 learner still searches its grid."""
    demos = lowest_foothold_demos()
    kw = dict(library_size=30, training_candidates=30, cv=3, Cs=4)
    trees_log, l1_log = [], []
    trees = learn_model(demos, "templates", "lambdarank", log=trees_log.append, **kw)
    learn_model(demos, "templates", "l1", log=l1_log.append, **kw)
    for group in ("front", "hind"):
        family = trees.functions[group].family("templates")
        assert family.rms == (ORDER_ONLY_RMS,) * 3 and family.search == ()
    assert not any("cv error" in line and "bandwidth rms (" in line for line in trees_log)
    assert sum("bandwidth rms" in line and "not searched" in line for line in trees_log) == 2
    assert sum("bandwidth rms (" in line for line in l1_log) >= 2 * len(BANDWIDTH_RMS_GRID)
