"""One suite of checks over every registered learner (footfall.learning.learner.LEARNERS).

Like scikit-learn's shared estimator checks: a learner is tested the moment it
registers. Every learner: fits a known ranking, deterministically, keeps the
fold units it is given whole, round-trips through its model file and scores a
candidate set at once as it scores each candidate alone. The linear learners
also: their path, weights and folds. ``ridge`` below is a learner of the test's
own, registered here without touching any other module.
"""

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.linear_model import RidgeClassifier

from footfall.core.errors import FootfallError
from footfall.core.state import nominal_state
from footfall.features.candidates import reachable_footholds
from footfall.features.family import Candidates
from footfall.features.terrain_features import TerrainFeatures
from footfall.learning.learner import LEARNERS, get_learner, register_learner
from footfall.learning.model import FootholdModel
from footfall.learning.ranker import FootholdRanker, LinearLearner, pairwise_error
from footfall.learning.train import TrainingDemo, learn_model
from maps import rough_map

RIDGE = LinearLearner("ridge", "ridge classifier (squared loss, L2), for the suite's own check",
                lambda C, tol, max_iter: RidgeClassifier(alpha=1.0 / C, fit_intercept=False,
                                                         tol=tol, max_iter=max_iter),
                lambda pairs, labels, n: np.logspace(-3.0, 1.0, n), logistic=False)


@pytest.fixture(scope="module", autouse=True)
def ridge_registered():
    register_learner(RIDGE)
    yield
    LEARNERS.unregister("ridge")


NAMES = ("l1", "l2", "svm", "ridge")  # the linear learners
ALL = NAMES + ("kernel", "lambdarank")  # every learner


def test_the_suite_covers_every_registered_learner():
    assert set(LEARNERS) == set(ALL)


def _toy(seed: int = 0, n_demos: int = 24, n: int = 15, d: int = 6):
    """Demonstrations whose choice maximises a known sparse score, with noise in the features."""
    rng = np.random.default_rng(seed)
    w = np.zeros(d)
    w[:2] = (2.0, -1.0)
    X = rng.normal(size=(n_demos * n, d))
    groups = np.repeat(np.arange(n_demos), n)
    y = np.zeros(n_demos * n, dtype=int)
    score = (X @ w).reshape(n_demos, n)
    y[np.arange(n_demos) * n + np.argmax(score, axis=1)] = 1
    return X, y, groups


@pytest.mark.parametrize("name", NAMES)
def test_fit_returns_the_estimator_and_its_learned_state(name):
    X, y, groups = _toy()
    ranker = FootholdRanker(learner=name, Cs=5, cv=4)
    assert ranker.fit(X, y, groups) is ranker
    assert ranker.coef_.shape == (X.shape[1],) and np.isfinite(ranker.coef_).all()
    assert ranker.scale_.shape == (X.shape[1],) and len(ranker.path_) >= 1
    assert ranker.C_ > 0 and ranker.lambda_ == pytest.approx(1 / ranker.C_)
    assert ranker.score(X, y, groups) > 0.5  # the known score is learned
    assert clone(ranker).get_params() == ranker.get_params()


@pytest.mark.parametrize("name", NAMES)
def test_the_same_data_gives_the_same_weights(name):
    X, y, groups = _toy(1)
    a = FootholdRanker(learner=name, Cs=5, cv=3).fit(X, y, groups)
    b = FootholdRanker(learner=name, Cs=5, cv=3).fit(X, y, groups)
    np.testing.assert_array_equal(a.coef_, b.coef_)
    np.testing.assert_array_equal([list(vars(p).values()) for p in a.path_],
                                  [list(vars(p).values()) for p in b.path_])  # NaN == NaN here


@pytest.mark.parametrize("name", NAMES)
def test_a_demonstration_is_never_split_across_folds(name):
    X, y, groups = _toy(2)
    ranker = FootholdRanker(learner=name, Cs=4, cv=4).fit(X, y, groups)
    assert len(ranker.fold_groups_) == 4
    held_out = np.concatenate([test for _, test in ranker.fold_groups_])
    assert np.array_equal(np.sort(held_out), np.unique(groups))  # each demonstration once
    for train, test in ranker.fold_groups_:
        assert np.intersect1d(train, test).size == 0
        assert np.union1d(train, test).size == np.unique(groups).size


def lowest_foothold_demos() -> list[TrainingDemo]:
    """Sixteen demonstrations on a rough map: the choice is the lowest foothold."""
    board = rough_map(seed=5)
    out = []
    for k, leg in enumerate(("LF", "RF", "LH", "RH") * 4):
        state = nominal_state(board, (-0.06 + 0.04 * (k // 4), 0.0), 0.0, leg)
        cand = reachable_footholds(board, state)[::4]
        out.append(TrainingDemo(board, state, cand, int(np.argmin(cand[:, 2]))))
    return out


@pytest.fixture(scope="module")
def demos():
    return lowest_foothold_demos()


@pytest.mark.parametrize("name", ALL)
def test_every_learner_learns_a_known_ranking_the_same_way_twice(name):
    X, y, groups = _toy(3, n_demos=40)
    learner = get_learner(name)
    fitted = learner.fit(X, y, groups, Cs=4, cv=3)
    again = learner.fit(X, y, groups, Cs=4, cv=3)
    scores = fitted.decision_function(X)
    assert scores.shape == (X.shape[0],) and np.isfinite(scores).all()
    np.testing.assert_array_equal(scores, again.decision_function(X))
    assert 0.0 <= fitted.cv_error_ < 0.25  # held-out pairs, not only the training ones
    assert pairwise_error(scores, y, groups) < 0.15


@pytest.mark.parametrize("name", ALL)
def test_every_learner_keeps_a_fold_unit_whole(name):
    """Folds grouped by run: with fewer runs than folds a learner must refuse (it grouped by
    the units, not by the demonstrations); with enough, its held-out error is measured."""
    X, y, groups = _toy(4, n_demos=30)
    runs = np.repeat(np.arange(30) // 10, 15)  # 3 runs of 10 demonstrations
    learner = get_learner(name)
    with pytest.raises(FootfallError, match="4-fold cross-validation needs at least 4 fold units"):
        learner.fit(X, y, groups, Cs=3, cv=4, units=runs)
    assert 0.0 <= learner.fit(X, y, groups, Cs=3, cv=3, units=runs).cv_error_ <= 1.0
    with pytest.raises(FootfallError, match="rows of one demonstration must share one fold unit"):
        learner.fit(X, y, groups, Cs=3, cv=3, units=np.arange(X.shape[0]) % 3)


@pytest.mark.parametrize("name", ALL)
def test_a_learned_model_round_trips_through_its_file_and_the_seed_fixes_it(name, demos,
                                                                            tmp_path):
    kw = dict(cv=3, Cs=4, training_candidates=30, seed=7)
    model = learn_model(demos, "terrain", name, **kw)
    again = learn_model(demos, "terrain", name, **kw)
    path = tmp_path / f"{name}.npz"
    model.save(path)
    back = FootholdModel.load(path)
    assert back.learner == name
    d = demos[0]
    c = Candidates.of_state(d.hmap, d.state, d.candidates, model.config)
    for leg in ("LF", "LH"):  # the values: a non-linear function's terrain part is validity
        values = model.reward_for(leg).values(c)
        assert np.isfinite(values).all() and np.ptp(values) > 0
        np.testing.assert_array_equal(back.reward_for(leg).values(c), values)
        np.testing.assert_array_equal(again.reward_for(leg).values(c), values)
    assert isinstance(model.functions["front"].families[0], TerrainFeatures)


@pytest.mark.parametrize("name", ALL)
def test_a_candidate_set_scores_at_once_as_each_candidate_alone(name, demos):
    """With the pose features (a state part): the values of all candidates in one call equal
    those of each candidate scored alone."""
    model = learn_model(demos, "terrain+pose", name, cv=3, Cs=4, training_candidates=30, seed=7)
    for d in demos[:4]:
        scorer = model.reward_for(d.state.swing_leg)
        together = scorer.values(Candidates.of_state(d.hmap, d.state, d.candidates, model.config))
        alone = [scorer.values(Candidates.of_state(d.hmap, d.state, d.candidates[k:k + 1],
                                                   model.config))[0]
                 for k in range(0, len(d.candidates), 7)]
        np.testing.assert_allclose(together[::7], alone, rtol=1e-12, atol=1e-12)
        assert np.isfinite(together).all()


def test_an_unknown_learner_is_refused_with_the_registered_names():
    with pytest.raises(FootfallError, match="unknown learner 'lasso'; use one of l1, l2, svm"):
        get_learner("lasso")
    X, y, groups = _toy()
    with pytest.raises(FootfallError, match="unknown learner"):
        FootholdRanker(learner="lasso").fit(X, y, groups)
    with pytest.raises(ValueError, match="already registered"):
        register_learner(LinearLearner("l1", "another", RIDGE.make, RIDGE.path))


def test_folds_grouped_by_run_never_split_a_run():
    X, y, groups = _toy(5, n_demos=40)
    runs = np.repeat(np.arange(40) % 8, 15)  # 8 runs, their steps interleaved in the data
    ranker = FootholdRanker(learner="l1", Cs=3, cv=4).fit(X, y, groups, units=runs)
    run_of = runs[::15]  # the run of each demonstration
    for train, test in ranker.fold_groups_:
        assert np.intersect1d(run_of[train], run_of[test]).size == 0  # a run is on one side
    held_out = np.concatenate([test for _, test in ranker.fold_groups_])
    assert np.array_equal(np.sort(held_out), np.arange(40))


def test_the_fold_unit_of_a_demonstration(demos):
    from footfall.learning.train import fold_unit

    d = demos[0]
    run = TrainingDemo(d.hmap, d.state, d.candidates, d.chosen, "run:12:step:3", "ab" * 32)
    walker = TrainingDemo(d.hmap, d.state, d.candidates, d.chosen, "walker:train", "cd" * 32)
    assert fold_unit(run, "run") == "run:12" and fold_unit(run, "board") == "board:" + "ab" * 32
    assert fold_unit(walker, "run") == "board:" + "cd" * 32  # a kinematic walk: its board
    keyed = TrainingDemo(d.hmap, d.state, d.candidates, d.chosen, "run:eval/a:b:step:7", "ab" * 32)
    assert fold_unit(keyed, "run") == "run:eval/a:b"
    assert fold_unit(run, "demonstration") == ""
    with pytest.raises(FootfallError, match="unknown fold grouping 'walk'"):
        fold_unit(run, "walk")
