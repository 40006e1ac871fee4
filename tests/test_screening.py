"""The L1 path's working sets (footfall.learning.screening): the same problem as a fit on all
columns, every left-out column proven zero."""

import numpy as np
import pytest
from sklearn.linear_model import LogisticRegression

from footfall.learning.ranker import FootholdRanker
from footfall.learning.screening import l1_objective, logistic_gradient, screened_l1_fit


def _problem(seed=0, n=600, d=120, k=6):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, d))
    w = np.zeros(d)
    w[rng.choice(d, k, replace=False)] = rng.uniform(1, 2, k) * rng.choice([-1, 1], k)
    y = np.where(X @ w + 3.0 * rng.logistic(size=n) > 0, 1.0, -1.0)  # far from separable
    return X, y


def _fit(C, X, y, tol=1e-8):
    return LogisticRegression(C=C, l1_ratio=1.0, solver="liblinear", fit_intercept=False,
                              tol=tol, max_iter=2000, random_state=0).fit(X, y).coef_.ravel()


def test_the_gradient_is_the_logistic_losss_negative_gradient():
    X, y = _problem(d=8)
    w = np.random.default_rng(1).normal(size=8) * 0.1
    rows = np.arange(0, X.shape[0], 2)
    eps = 1e-6
    numeric = np.array([(l1_objective(X[rows], y[rows], w - eps * e, 1.0)
                         - l1_objective(X[rows], y[rows], w + eps * e, 1.0)) / (2 * eps)
                        for e in np.eye(8)])  # -d(objective)/dw = -d(loss)/dw - sign(w)
    np.testing.assert_allclose(logistic_gradient(X, y, w, rows), numeric + np.sign(w),
                               rtol=1e-5, atol=1e-5)


@pytest.mark.parametrize("C", [0.01, 0.05, 0.2])
def test_a_screened_fit_solves_the_whole_problem(C):
    X, y = _problem()
    rows = np.arange(X.shape[0])[::2] if C == 0.05 else np.arange(X.shape[0])
    full = _fit(C, X[rows], y[rows])
    screened, fits = screened_l1_fit(lambda c, x, t: _fit(c, x, t), C, X, y, rows,
                                     w_prev=None)
    # the same optimum (solved tightly): the same support, weights and objective
    assert np.array_equal(full != 0, screened != 0)
    np.testing.assert_allclose(screened, full, atol=1e-6)
    lam = 1.0 / C
    g = logistic_gradient(X, y, screened, rows)
    assert np.all(np.abs(g[screened == 0]) <= lam * (1 + 1e-9))  # every zero column optimal
    assert fits >= 1


def test_a_working_set_that_misses_a_column_is_grown_until_none_breaks_the_condition():
    X, y = _problem(seed=1)
    # a step along a path: from the optimum at C = 0.02 the first set misses columns at 0.1
    start, C = _fit(0.02, X, y), 0.1
    full = _fit(C, X, y)
    seen = []

    def fit(c, x, t):
        seen.append(x.shape[1])
        return _fit(c, x, t)

    screened, fits = screened_l1_fit(fit, C, X, y, np.arange(X.shape[0]), w_prev=start)
    assert fits == len(seen) >= 2  # the first set was wrong, and the check found it
    assert all(a < b for a, b in zip(seen, seen[1:]))  # each fit saw more columns
    assert seen[-1] < X.shape[1]  # ... but never needed all of them
    np.testing.assert_allclose(screened, full, atol=1e-6)


def test_the_screened_path_picks_the_unscreened_lambda_and_weights_within_tolerance():
    rng = np.random.default_rng(3)
    n_demo, m, d = 40, 25, 150
    X = rng.normal(size=(n_demo * m, d))
    w = np.zeros(d)
    w[:5] = [2, -1.5, 1, 1, -2]
    r = (X @ w + 2.0 * rng.gumbel(size=X.shape[0])).reshape(n_demo, m)
    y = np.zeros((n_demo, m), dtype=int)
    y[np.arange(n_demo), r.argmax(axis=1)] = 1
    groups = np.repeat(np.arange(n_demo), m)
    kw = dict(learner="l1", Cs=8, cv=4, tol=1e-8, max_iter=100000)
    a = FootholdRanker(**kw).fit(X, y.ravel(), groups)
    b = FootholdRanker(**kw, screening=False).fit(X, y.ravel(), groups)
    assert a.C_ == b.C_
    assert [p.error for p in a.path_] == pytest.approx([p.error for p in b.path_], abs=1e-3)
    np.testing.assert_allclose(a.coef_, b.coef_, atol=1e-4 * np.abs(b.coef_).max())
    again = FootholdRanker(**kw).fit(X, y.ravel(), groups)  # deterministic
    assert np.array_equal(again.coef_, a.coef_)
