"""The rank learner: pairwise transform, grouped folds, sparse recovery, estimator API."""

import numpy as np
import pytest
from sklearn.linear_model import LogisticRegression

from footfall.core.errors import FootfallError
from footfall.learning.ranker import (
    FootholdRanker,
    grouped_folds,
    pairwise_error,
    pairwise_transform,
)


def test_pairwise_transform_on_a_hand_made_example():
    X = np.array([[1.0, 0.0], [3.0, 1.0], [0.0, 2.0],   # demo 7: chosen is row 1
                  [5.0, 5.0], [4.0, 4.0]])               # demo 2: chosen is row 3
    y = np.array([0, 1, 0, 1, 0])
    groups = np.array([7, 7, 7, 2, 2])
    pairs, labels, g = pairwise_transform(X, y, groups)
    # Demonstrations are taken in sorted order of their ids; then the mirrored copies.
    expected = np.array([[1.0, 1.0],                      # demo 2: x3 - x4
                         [2.0, 1.0], [3.0, -1.0]])        # demo 7: x1 - x0, x1 - x2
    np.testing.assert_array_equal(pairs, np.concatenate([expected, -expected]))
    np.testing.assert_array_equal(labels, [1, 1, 1, -1, -1, -1])
    np.testing.assert_array_equal(g, [2, 7, 7, 2, 7, 7])
    once, lab, _ = pairwise_transform(X, y, groups, mirrored=False)
    np.testing.assert_array_equal(once, expected)
    assert (lab == 1).all()


@pytest.mark.parametrize("y, groups, match", [
    ([1, 1, 0], [0, 0, 0], "exactly one chosen"),
    ([0, 0, 0], [0, 0, 0], "exactly one chosen"),
    ([1, 1, 0], [0, 1, 1], "at least two candidates"),
    ([1.5, 0, 0], [0, 0, 0], "whole relevance levels"),
    ([1, -1, 0], [0, 0, 0], "whole relevance levels"),
    ([31, 0, 0], [0, 0, 0], "whole relevance levels"),
    ([2, 2, 1], [0, 0, 0], "exactly one chosen"),
])
def test_bad_demonstrations_are_rejected(y, groups, match):
    with pytest.raises(FootfallError, match=match):
        pairwise_transform(np.zeros((3, 2)), np.array(y), np.array(groups))
    with pytest.raises(FootfallError, match="NaN"):
        pairwise_transform(np.array([[np.nan], [0.0]]), np.array([1, 0]), np.array([0, 0]))


def test_graded_levels_pair_each_candidate_with_one_of_every_level_above_it():
    # one demonstration: row 2 chosen (3); rows 0 and 4 within the margin (2); row 1 short (1);
    # row 3 refused (0). Each row pairs with the chosen row and the first row of every level
    # between: 0 -> (2); 1 -> (2), (0); 3 -> (2), (0), (1); 4 -> (2).
    X = np.arange(10.0).reshape(5, 2) ** 2
    y = np.array([2, 1, 3, 0, 2])
    pairs, labels, g = pairwise_transform(X, y, np.zeros(5, dtype=int), mirrored=False)
    better = [2, 2, 0, 2, 0, 1, 2]
    worse = [0, 1, 1, 3, 3, 3, 4]
    np.testing.assert_array_equal(pairs, X[better] - X[worse])
    assert (labels == 1).all() and (g == 0).all()
    # a score that orders the levels right makes no error; one that swaps the top two levels
    # errs on the pairs of the chosen row with the rows of level 2 only
    assert pairwise_error(np.array([2.0, 1.0, 3.0, 0.0, 2.5]), y, np.zeros(5)) == 0.0
    assert pairwise_error(np.array([3.0, 1.0, 2.0, 0.0, 2.5]), y, np.zeros(5)) == 2 / 7


def test_a_choice_is_the_lowest_grading():
    # levels 0 / 1 give the (chosen, other) pairs, as a choice always did
    rng = np.random.default_rng(3)
    X = rng.normal(size=(12, 3))
    groups = np.repeat([4, 1, 9], 4)
    y = np.zeros(12, dtype=int)
    y[[2, 4, 11]] = 1
    pairs, _, g = pairwise_transform(X, y, groups, mirrored=False)
    chosen_of = {1: 4, 4: 2, 9: 11}
    expected = [(chosen_of[k], i) for k in (1, 4, 9) for i in np.flatnonzero(groups == k)
                if i != chosen_of[k]]
    np.testing.assert_array_equal(pairs, np.array([X[c] - X[i] for c, i in expected]))
    np.testing.assert_array_equal(g, [groups[i] for _, i in expected])


def test_grouped_folds_never_split_a_demonstration():
    rng = np.random.default_rng(0)
    groups = np.repeat(np.arange(23), rng.integers(2, 30, size=23))
    folds = grouped_folds(groups, 5)
    assert len(folds) == 5
    seen = np.zeros(groups.size, dtype=int)
    for train, test in folds:
        assert not set(groups[train]) & set(groups[test])
        seen[test] += 1
    assert (seen == 1).all()  # every pair is held out exactly once
    with pytest.raises(FootfallError, match="at least 5 demonstrations"):
        grouped_folds(np.repeat(np.arange(3), 4), 5)


def _synthetic(seed=1, d=200, n_demo=60, m=60, k=8, noise=0.5):
    rng = np.random.default_rng(seed)
    support = rng.choice(d, k, replace=False)
    w = np.zeros(d)
    w[support] = rng.uniform(1, 2, k) * rng.choice([-1, 1], k)
    X = rng.normal(size=(n_demo * m, d))
    groups = np.repeat(np.arange(n_demo), m)
    r = (X @ w + rng.gumbel(size=X.shape[0]) * noise).reshape(n_demo, m)
    y = np.zeros((n_demo, m), dtype=int)
    y[np.arange(n_demo), r.argmax(axis=1)] = 1
    return X, y.ravel(), groups, w


def test_l1_learner_recovers_a_known_sparse_support():
    X, y, groups, w = _synthetic()
    est = FootholdRanker(learner="l1", Cs=10, cv=5).fit(X, y, groups)
    support = set(np.flatnonzero(w))
    selected = set(np.flatnonzero(est.coef_))
    assert support <= selected  # every true feature is kept ...
    assert len(selected) < 0.25 * X.shape[1]  # ... and most of the others are dropped
    top = set(np.argsort(-np.abs(est.coef_))[:len(support)])
    assert top == support  # the largest weights are exactly the true ones
    assert (np.sign(est.coef_[list(support)]) == np.sign(w[list(support)])).all()
    assert est.score(X, y, groups) > 0.8
    assert est.lambda_ == pytest.approx(1.0 / est.C_)


def test_fitting_once_with_double_c_equals_fitting_the_mirrored_pairs():
    X, y, groups, _ = _synthetic(seed=3, d=20, n_demo=20, m=15)
    est = FootholdRanker(learner="l2", Cs=[0.05], cv=2, tol=1e-10).fit(X, y, groups)
    pairs, labels, _ = pairwise_transform(X, y, groups)
    scale = pairs.std(axis=0)
    ref = LogisticRegression(C=0.05, l1_ratio=0.0, solver="liblinear", fit_intercept=False,
                             tol=1e-10, max_iter=10000).fit(pairs / scale, labels)
    np.testing.assert_allclose(est.coef_, ref.coef_.ravel() / scale, rtol=1e-5, atol=1e-8)


@pytest.mark.parametrize("learner", ["l1", "l2", "svm"])
def test_every_learner_ranks_the_synthetic_choice_first(learner):
    X, y, groups, w = _synthetic(seed=4, d=30, n_demo=40, m=30, k=4)
    est = FootholdRanker(learner=learner, Cs=6, cv=4).fit(X, y, groups)
    assert est.score(X, y, groups) > 0.7
    assert np.corrcoef(est.coef_, w)[0, 1] > 0.8


def test_estimator_api():
    est = FootholdRanker(learner="l1", Cs=3)
    assert est.get_params()["Cs"] == 3 and not hasattr(est, "coef_")  # the constructor only stores
    from sklearn.exceptions import NotFittedError
    with pytest.raises(NotFittedError):
        est.decision_function(np.zeros((2, 3)))
    with pytest.raises(FootfallError, match="unknown learner"):
        FootholdRanker(learner="tree").fit(np.zeros((4, 2)), np.array([1, 0, 1, 0]),
                                           np.array([0, 0, 1, 1]))
    X, y, groups, _ = _synthetic(seed=5, d=10, n_demo=12, m=8, k=2)
    fitted = FootholdRanker(Cs=3, cv=3).fit(X, y, groups)
    assert fitted is not None and fitted.coef_.shape == (10,)
    with pytest.raises(FootfallError, match="expected 10 features"):
        fitted.decision_function(np.zeros((2, 3)))


def test_min_error_selection_is_never_sparser_than_the_one_standard_error_rule():
    X, y, groups, _ = _synthetic(seed=5)
    se = FootholdRanker(learner="l1", Cs=8, cv=4, selection="1se").fit(X, y, groups)
    best = FootholdRanker(learner="l1", Cs=8, cv=4, selection="min").fit(X, y, groups)
    errors = [p.error for p in best.path_]
    assert best.cv_error_ == pytest.approx(min(errors))
    assert best.C_ >= se.C_  # the 1-SE rule picks the same or a stronger lambda
    assert np.count_nonzero(best.coef_) >= np.count_nonzero(se.coef_)
    with pytest.raises(FootfallError, match="selection rule"):
        FootholdRanker(selection="median").fit(X, y, groups)


def test_refitting_gives_bit_identical_paths_and_weights():
    # liblinear's random generator is process-wide: fits racing in threads would differ.
    X, y, groups, _ = _synthetic(seed=6)
    a = FootholdRanker(learner="l1", Cs=6, cv=5).fit(X, y, groups)
    b = FootholdRanker(learner="l1", Cs=6, cv=5).fit(X, y, groups)
    assert [p.error for p in a.path_] == [p.error for p in b.path_]
    assert a.coef_.tobytes() == b.coef_.tobytes()
