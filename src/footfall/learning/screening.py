"""Working sets for the L1 path: fit each value of the regularisation on the columns that can be
non-zero, and check afterwards that every other column is zero at the optimum.

The L1-regularised logistic regression of the ranker (paper Eq. 5, in
liblinear's form) minimises

    ||w||_1 + C sum_i log(1 + exp(-y_i w.x_i)),

whose optimum leaves a column j at zero exactly when |g_j(w)| <= 1 / C, with

    g_j(w) = sum_i y_i x_ij sigma(-y_i w.x_i)      (sigma: the logistic function)

the loss's negative gradient per unit of C (the Karush-Kuhn-Tucker
condition). Along a path of increasing C most of ~1 000 template columns
stay at zero, and a fit's cost -- liblinear's copy of the data into its own
format is the larger part of a fit at strong regularisation -- grows with
the columns it is given. So each fit starts from the *working set* of the
neighbouring solution on the path: the columns non-zero there and those
whose gradient there breaks the condition at the new C (the columns the
new C can move off zero). After the fit every column left out is checked
against the condition at the new weights; any that breaks it joins the set
and the fit is repeated. The weights are then a solution of the whole
problem to the solver's tolerance, the same as a fit on all columns --
not bit for bit, since liblinear visits the columns in another order:
`footfall bench learning` prints both objectives.

This is the ever-active / KKT-check strategy of path solvers such as
glmnet (Friedman, Hastie and Tibshirani, J. Stat. Softw. 2010; Tibshirani
et al., "Strong rules for discarding predictors in lasso-type problems",
JRSS B 2012). The strong rule itself (2 lambda - lambda_prev) keeps every
column on footfall's coarse path (C grows 2.6x a point), so the looser
rule above is used.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.special import expit

Fit = Callable[[float, np.ndarray, np.ndarray], np.ndarray]  # (C, X, y) -> weights (d,)


def logistic_gradient(X: np.ndarray, y: np.ndarray, w: np.ndarray,
                      rows: np.ndarray | None = None) -> np.ndarray:
    """g(w) = X^T (y * sigma(-y * X w)) over ``rows`` of X (all rows if None), (d,).

    ``rows`` selects without copying X: the other rows get weight 0.
    """
    nz = np.flatnonzero(w)
    m = y * (X[:, nz] @ w[nz]) if nz.size < X.shape[1] // 4 else y * (X @ w)
    r = y * expit(-m)
    if rows is not None:
        keep = np.zeros(X.shape[0], dtype=bool)
        keep[rows] = True
        r[~keep] = 0.0
    return X.T @ r


def l1_objective(X: np.ndarray, y: np.ndarray, w: np.ndarray, C: float) -> float:
    """||w||_1 + C sum_i log(1 + exp(-y_i w.x_i)): what the L1 fit minimises."""
    return float(np.abs(w).sum() + C * np.logaddexp(0.0, -y * (X @ w)).sum())


def screened_l1_fit(fit: Fit, C: float, X: np.ndarray, y: np.ndarray, rows: np.ndarray, *,
                    w_prev: np.ndarray | None) -> tuple[np.ndarray, int]:
    """The L1 logistic weights (d,) at ``C`` on ``rows`` of (X, y), fitted by ``fit`` on a
    working set grown from ``w_prev`` (weights at a neighbouring C; None: zero), every column
    outside it checked; and how many fits that took.
    """
    d = X.shape[1]
    lam = 1.0 / C
    w0 = np.zeros(d) if w_prev is None else w_prev
    active = (w0 != 0) | (np.abs(logistic_gradient(X, y, w0, rows)) > lam)
    for fits in range(1, d + 2):
        w = np.zeros(d)
        if active.any():
            cols = np.flatnonzero(active)
            w[cols] = fit(C, X[np.ix_(rows, cols)], y[rows])
        missed = ~active & (np.abs(logistic_gradient(X, y, w, rows)) > lam)
        if not missed.any():
            return w, fits
        active |= missed
    raise AssertionError("a column broke the condition with every column fitted")  # unreachable
