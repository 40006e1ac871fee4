"""Learning a foothold ranking function from demonstrations (paper §II-C, §III-B).

A demonstration says the chosen foothold c beats every other candidate i of
its set F: w^T (x_c - x_i) > 0 (Eq. 3). :func:`pairwise_transform` turns
demonstrations into those difference vectors, labelled +1, with their
mirrored copies -(x_c - x_i) labelled -1 so that a classifier sees two
classes; :class:`FootholdRanker` standardises them and fits a linear
classifier without intercept -- L1-regularised logistic regression (Eq. 5),
which selects a sparse set of features (templates), or L2 logistic regression
or a linear SVM for comparison -- choosing lambda = 1/C by k-fold
cross-validation with folds grouped by demonstration.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.exceptions import ConvergenceWarning
from sklearn.linear_model import LogisticRegression
from sklearn.model_selection import GroupKFold
from sklearn.svm import LinearSVC
from sklearn.utils.validation import check_is_fitted

from footfall.core.errors import FootfallError
from footfall.features.family import FeatureFamily
from footfall.learning.function import LinearFunction, RankingFunction
from footfall.learning.learner import Learner, get_learner, register_learner
from footfall.learning.levels import (  # noqa: F401 (pairwise_error: every learner's measure)
    _check_demonstrations,
    chosen_rows,
    level_pairs,
    pairwise_error,
)
from footfall.learning.screening import screened_l1_fit

SELECTIONS = ("1se", "min")  # lambda: one-standard-error rule, or the smallest CV error
L2_LOG_C = (-6.0, 0.0)  # log10 of the smallest and largest C on the L2 / SVM path
L1_LOG_SPAN = (0.3, 4.0)  # log10 of the L1 path's ends relative to the smallest C with a weight


# ---------------------------------------------------------------- learners
@dataclass(frozen=True)
class LinearLearner(Learner):
    """A linear classifier the ranker fits on pairwise differences: a linear learner.

    ``make(C, tol, max_iter)`` returns an unfitted scikit-learn classifier
    *without intercept* whose fitted ``coef_`` is the weight vector (a
    pairwise model has no intercept: x_c - x_i is symmetric around 0), with
    any randomness fixed so that a fit is reproducible. ``path(pairs,
    labels, n)`` gives ``n`` increasing values of C = 1 / lambda to
    cross-validate, for standardised pairs (m, d) and labels (m,) of +-1.
    It makes a :class:`~footfall.learning.function.LinearFunction`.
    """

    name: str  # registry key, e.g. "l1"
    description: str  # one line for --help and reports
    make: Callable[[float, float, int], object]  # (C, tol, max_iter) -> classifier
    path: Callable[[np.ndarray, np.ndarray, int], np.ndarray]  # -> (n,) C values, increasing
    logistic: bool = True  # the loss is the logistic loss (its held-out value is reported)
    function_type: type[RankingFunction] = LinearFunction
    ranks_columns: bool = True
    screened: bool = False  # an L1 path: fitted on the columns that can leave zero (screening)

    def fit(self, X: np.ndarray, y: np.ndarray, groups: np.ndarray, *, Cs=10, cv: int = 5,
            selection: str = "1se", units: np.ndarray | None = None) -> FootholdRanker:
        """:class:`FootholdRanker` with this learner, fitted."""
        return FootholdRanker(learner=self.name, Cs=Cs, cv=cv, selection=selection).fit(
            X, y, groups, units)

    def function(self, fitted: FootholdRanker, families: tuple[FeatureFamily, ...],
                 n_demonstrations: int) -> LinearFunction:
        """Per family its kept columns (non-zero weights) with their raw weights and scales."""
        kept, coef, scale, family_info = [], [], [], {}
        start = 0
        for family in families:
            stop = start + len(family.columns())
            w, s = fitted.coef_[start:stop], fitted.scale_[start:stop]
            reduced, keep = family.select(w != 0)
            kept.append(reduced)
            coef.append(w[keep])
            scale.append(s[keep])
            family_info.update(reduced.info())
            start = stop
        info = {"lambda": fitted.lambda_, "C": fitted.C_, "cv_error": fitted.cv_error_,
                "path": [vars(p) for p in fitted.path_], "n_demonstrations": n_demonstrations,
                **family_info, "n_nonzero": int(np.count_nonzero(fitted.coef_))}
        return LinearFunction(tuple(kept), tuple(coef), tuple(scale), info)

    def importance(self, fitted: FootholdRanker) -> np.ndarray:
        """The weights' sizes on standardised columns, |coef_| * scale_ (0: left at zero)."""
        return np.abs(fitted.coef_ * fitted.scale_)


def _linear(name: str) -> LinearLearner:
    """The registered linear learner called ``name``, or a clear error."""
    learner = get_learner(name)
    if not isinstance(learner, LinearLearner):
        raise FootfallError(f"learner {name!r} is not a linear classifier on pairwise "
                            f"differences")
    return learner


def _l1_path(pairs: np.ndarray, labels: np.ndarray, n: int) -> np.ndarray:
    # The smallest C at which a weight leaves zero: 1 / max |X^T y| / 2 (logistic loss).
    c_min = 2.0 / np.max(np.abs(pairs.T @ labels))
    return c_min * np.logspace(L1_LOG_SPAN[0], L1_LOG_SPAN[1], n)


def _l2_path(pairs: np.ndarray, labels: np.ndarray, n: int) -> np.ndarray:
    # L2 and the SVM have no such end: as C -> 0 their weights shrink toward
    # the direction of the mean pairwise difference, whose ranking no longer
    # changes with C. Six decades reach from that limit to weak regularisation.
    return np.logspace(L2_LOG_C[0], L2_LOG_C[1], n)


def _logistic(l1_ratio: float) -> Callable[[float, float, int], object]:
    # liblinear shuffles the data: a fixed seed makes every fit reproducible.
    return lambda C, tol, max_iter: LogisticRegression(
        C=C, l1_ratio=l1_ratio, solver="liblinear", fit_intercept=False, tol=tol,
        max_iter=max_iter, random_state=0)


register_learner(LinearLearner("l1", "L1-regularised logistic regression (paper Eq. 5): sparse, "
                               "selects templates", _logistic(1.0), _l1_path, screened=True))
register_learner(LinearLearner("l2", "L2-regularised logistic regression", _logistic(0.0), _l2_path))
register_learner(LinearLearner(
    "svm", "linear SVM (hinge loss, L2)",
    lambda C, tol, max_iter: LinearSVC(C=C, fit_intercept=False, tol=tol, max_iter=max_iter,
                                       dual=True, random_state=0),
    _l2_path, logistic=False))
BUILTIN_LEARNERS = ("l1", "l2", "svm")  # the three the offline experiment compares


def pairwise_transform(X: np.ndarray, y: np.ndarray, groups: np.ndarray,
                       mirrored: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pairwise difference vectors of demonstrations (paper Eq. 3), between relevance levels.

    Parameters
    ----------
    X : array of shape (n_candidates, n_features)
        Features of the candidates of all demonstrations, stacked.
    y : array of shape (n_candidates,)
        Each candidate's relevance level, a whole number in [0, MAX_LEVEL]: the chosen
        candidate alone at its demonstration's highest level (a choice: 1 for it, 0 for the
        others; graded supervision: more levels, :mod:`footfall.learning.supervision`).
    groups : array of shape (n_candidates,)
        The demonstration each candidate belongs to.
    mirrored : bool
        Also emit -(x_b - x_w) with label -1 for every pair.

    Returns
    -------
    pairs : array of shape (n_pairs, n_features)
        x_b - x_w for every pair of :func:`level_pairs` (for a choice: x_c - x_i for every
        other candidate i of each demonstration), demonstrations in the order of their
        ``groups`` values (then, if ``mirrored``, their negatives).
    labels : array of shape (n_pairs,) of +1 / -1
    pair_groups : array of shape (n_pairs,), the demonstration of each pair
    """
    X = np.asarray(X, dtype=np.float64)
    y = np.asarray(y)
    groups = np.asarray(groups)
    _check_demonstrations(X, y, groups)
    better, worse = level_pairs(y, groups)
    pairs = X[better] - X[worse]
    pair_groups = groups[worse]
    labels = np.ones(pairs.shape[0])
    if mirrored:
        pairs = np.concatenate([pairs, -pairs])
        labels = np.concatenate([labels, -labels])
        pair_groups = np.concatenate([pair_groups, pair_groups])
    return pairs, labels, pair_groups


def grouped_folds(pair_groups: np.ndarray, n_splits: int, units: np.ndarray | None = None
                  ) -> list[tuple[np.ndarray, np.ndarray]]:
    """K folds of pair (or row) indices; all pairs of one demonstration fall in the same fold,
    and with ``units`` (the fold unit of each pair: its run or board) all pairs of one unit.

    Neighbouring steps of one run are not independent: folds grouped by run
    (or board) hold out whole runs, so that the held-out error measures
    learning on terrain and states the learner has not seen.
    """
    labels = pair_groups if units is None else np.asarray(units)
    if labels.shape != np.shape(pair_groups):
        raise FootfallError("need one fold unit per pair")
    n_groups = np.unique(labels).size
    if n_groups < n_splits:
        what = "demonstrations" if units is None else "fold units (runs or boards)"
        raise FootfallError(f"{n_splits}-fold cross-validation needs at least {n_splits} "
                            f"{what}, got {n_groups}")
    return list(GroupKFold(n_splits=n_splits).split(labels, groups=labels))


def units_of(groups: np.ndarray, units: np.ndarray | None, of: np.ndarray) -> np.ndarray | None:
    """The fold unit of each entry of ``of`` (demonstration ids), from per-row ``groups`` and
    ``units``; None without units. A demonstration's rows must share one unit."""
    if units is None:
        return None
    groups, units = np.asarray(groups), np.asarray(units)
    if units.shape != groups.shape:
        raise FootfallError("need one fold unit per candidate row")
    uniq, first = np.unique(groups, return_index=True)
    unit_of_group = units[first]
    if np.any(units != unit_of_group[np.searchsorted(uniq, groups)]):
        raise FootfallError("the rows of one demonstration must share one fold unit")
    return unit_of_group[np.searchsorted(uniq, np.asarray(of))]


def select_on_path(errors: np.ndarray, stds: np.ndarray, n_folds: int, selection: str) -> int:
    """The index picked on a path ordered from the simplest model to the most complex: the
    smallest held-out error (``"min"``), or the simplest within one standard error of it
    (``"1se"``: as good within the noise of the folds, and simpler)."""
    if selection not in SELECTIONS:
        raise FootfallError(f"unknown selection rule {selection!r}; use one of "
                            f"{', '.join(SELECTIONS)}")
    best = int(np.argmin(errors))
    if selection == "1se":
        bound = errors[best] + stds[best] / np.sqrt(n_folds)
        best = int(np.flatnonzero(errors <= bound + 1e-12)[0])
    return best


def _fit_coef(learner: LinearLearner, C: float, X: np.ndarray, y: np.ndarray, tol: float,
              max_iter: int) -> np.ndarray:
    clf = learner.make(C, tol, max_iter)
    with warnings.catch_warnings():
        # On separable folds liblinear may stop at max_iter: the path goes on.
        warnings.simplefilter("ignore", ConvergenceWarning)
        clf.fit(X, y)
    return clf.coef_.ravel().copy()


def _fit_rows(learner: LinearLearner, C: float, X: np.ndarray, y: np.ndarray,
              rows: np.ndarray | None,
              tol: float, max_iter: int, screen: bool, start: np.ndarray | None = None
              ) -> np.ndarray:
    """The weights at ``C`` on ``rows`` of (X, y) (None: all, not copied): with ``screen`` on a
    working set of columns grown from ``start`` (weights at a neighbouring C;
    :mod:`footfall.learning.screening`), else on all columns at once."""
    if not screen:
        return _fit_coef(learner, C, X if rows is None else X[rows],
                         y if rows is None else y[rows], tol, max_iter)
    rows = np.arange(X.shape[0]) if rows is None else rows
    return screened_l1_fit(lambda c, x, t: _fit_coef(learner, c, x, t, tol, max_iter), C, X, y,
                           rows, w_prev=start)[0]


def _cross_validate(learner: LinearLearner, Cs: np.ndarray, X: np.ndarray, y: np.ndarray,
                    folds: list, tol: float, max_iter: int, screen: bool
                    ) -> tuple[list["PathPoint"], list[list[np.ndarray]]]:
    """Held-out errors along the path, the folds of one C fitted one after another; and the
    weights of every fold at every point of it.

    With ``screen`` (the L1 path) each fold at each C is fitted on a working
    set of columns grown from that fold's weights at the previous C
    (:mod:`footfall.learning.screening`): the same problem, solved to the
    solver's tolerance, in about half the time.

    The path runs from strong to weak regularisation and stops once the
    held-out error has risen for two values in a row past its minimum: the
    weakly regularised fits are the slow ones, and the selection never
    reaches them.

    The folds are NOT fitted in parallel threads: scikit-learn's liblinear
    (logistic regression and LinearSVC alike) draws its coordinate order
    from one process-wide random generator (``set_seed`` in its
    ``newrand.h``), so concurrent fits race for it and the cross-validation
    errors -- and with them lambda and the bandwidths -- would change from
    run to run. Sequential fits give the same model for the same seed.
    """
    near: list[np.ndarray | None] = [None] * len(folds)  # per fold: weights at the previous C
    weights: list[list[np.ndarray]] = []  # per path point, per fold

    def one(k: int, C: float, train: np.ndarray, test: np.ndarray) -> tuple[float, float, int]:
        w = _fit_rows(learner, C, X, y, train, tol, max_iter, screen, near[k])
        near[k] = w
        weights[-1].append(w)
        margin = y[test] * (X[test] @ w)
        return float(np.mean(margin <= 0)), float(np.mean(np.logaddexp(0.0, -margin))), \
            int(np.count_nonzero(w))

    path: list[PathPoint] = []
    for C in Cs:  # the regularisation path: a handful of values
        weights.append([])
        res = [one(k, C, *f) for k, f in enumerate(folds)]
        errors = np.array([r[0] for r in res])
        path.append(PathPoint(float(C), float(errors.mean()), float(errors.std()),
                              float(np.mean([r[1] for r in res])) if learner.logistic
                              else float("nan"), float(np.mean([r[2] for r in res]))))
        if _path_turned([p.error for p in path]):
            break
    return path, weights


def _path_turned(errors: Sequence[float]) -> bool:
    """Whether a path of held-out errors, simplest model first, has risen for two values in a
    row past its minimum: where the linear path stops (the selection never reaches the later,
    costlier values)."""
    k = int(np.argmin(errors))
    return len(errors) - k > 2 and errors[-1] > errors[-2] > errors[k]


@dataclass
class PathPoint:
    """Cross-validation result of one value of the regularisation."""

    C: float  # inverse regularisation strength (lambda = 1 / C)
    error: float  # mean held-out pairwise misclassification rate
    error_std: float  # its standard deviation over folds
    log_loss: float  # mean held-out logistic loss (NaN for the SVM)
    n_nonzero: float  # mean number of non-zero weights over folds


class FootholdRanker(BaseEstimator):
    """A linear foothold ranking function learned from demonstrations.

    Parameters
    ----------
    learner : str
        A registered linear learner (:class:`LinearLearner`): ``"l1"`` or ``"l2"``
        regularised logistic regression, or ``"svm"``, a linear SVM (hinge
        loss, L2), all without intercept, on pairwise differences.
    Cs : int or array-like
        The regularisation path: values of C = 1 / lambda, or how many
        log-spaced values the learner's path rule gives (L1: from just above
        the smallest C that keeps a weight non-zero, upward over 3.7 decades;
        L2 and the SVM: over ``L2_LOG_C``).
    cv : int
        Number of folds, grouped by demonstration (or by the ``units`` given to
        :meth:`fit`: runs or boards).
    selection : {"1se", "min"}
        How lambda is picked from the path: the strongest regularisation
        within one standard error of the smallest CV error (sparser), or
        the smallest CV error.
    tol, max_iter : solver tolerance and iteration limit.
    screening : bool
        Fit an L1 path on working sets of columns, every other column checked
        to stay at zero (:mod:`footfall.learning.screening`): the same problem
        solved to the same tolerance, about half the time. ``False`` gives
        every fit all columns (the reference).

    Attributes
    ----------
    coef_ : array of shape (n_features,)
        Weights on the *raw* features: rank candidates by ``X @ coef_``.
    scale_ : array of shape (n_features,)
        Standard deviation of each feature over the training pairs; the
        classifier was fitted to ``pairs / scale_``.
    C_ : float
        The chosen C (``lambda_ = 1 / C_``).
    path_ : list of PathPoint
        Cross-validation results along the path.
    fold_groups_ : list of (train, test) arrays
        The demonstrations (``groups`` values) in each fold's training and
        held-out part: a demonstration is never split between them.
    """

    def __init__(self, learner: str = "l1", Cs: int | np.ndarray = 10, cv: int = 5,
                 tol: float = 1e-4, max_iter: int = 2000, selection: str = "1se",
                 screening: bool = True):
        self.learner = learner
        self.screening = screening
        self.selection = selection
        self.Cs = Cs
        self.cv = cv
        self.tol = tol
        self.max_iter = max_iter

    def _path(self, pairs: np.ndarray, labels: np.ndarray) -> np.ndarray:
        if not np.isscalar(self.Cs):
            Cs = np.sort(np.asarray(self.Cs, dtype=np.float64))
            if Cs.size == 0 or not (np.isfinite(Cs) & (Cs > 0)).all():
                raise FootfallError("Cs must be finite and positive")
            return Cs
        n = int(self.Cs)
        if n < 1:
            raise FootfallError("Cs must be at least 1")
        return _linear(self.learner).path(pairs, labels, n)

    def fit(self, X: np.ndarray, y: np.ndarray, groups: np.ndarray,
            units: np.ndarray | None = None) -> "FootholdRanker":
        """Learn from stacked candidate features of demonstrations (see :func:`pairwise_transform`).

        ``units`` (n_candidates,), if given, names the fold unit of each row
        (its demonstration's run or board): the folds never split one.

        The mirrored pair set holds every pair twice, once with each sign, and
        a linear classifier without intercept has the same loss on (x, +1)
        and (-x, -1). Fitting it is therefore exactly fitting each pair once
        at twice the C; that is what is solved (half the work, the same
        weights). Pairs alternate in sign so that the solver sees two classes.
        """
        learner = _linear(self.learner)
        if int(self.cv) < 2:
            raise FootfallError("cv needs at least 2 folds")
        if self.selection not in SELECTIONS:
            raise FootfallError(f"unknown selection rule {self.selection!r}; use one of "
                                f"{', '.join(SELECTIONS)}")
        screen = learner.screened and self.screening
        pairs, _, pair_groups = pairwise_transform(X, y, groups, mirrored=False)
        scale = np.sqrt(np.mean(pairs * pairs, axis=0))  # std over the mirrored set: mean is 0
        scale[scale < 1e-12] = 1.0  # a constant feature carries no preference
        signs = np.where(np.arange(pairs.shape[0]) % 2 == 0, 1.0, -1.0)
        Xs = pairs / scale * signs[:, None]
        labels = signs
        Cs = self._path(Xs, labels)
        folds = grouped_folds(pair_groups, int(self.cv), units_of(groups, units, pair_groups))
        self.fold_groups_ = [(np.unique(pair_groups[tr]), np.unique(pair_groups[te]))
                             for tr, te in folds]
        self.path_, fold_weights = _cross_validate(learner, 2.0 * Cs, Xs, labels, folds,
                                                   self.tol, self.max_iter, screen)
        for point, C in zip(self.path_, Cs):
            point.C = float(C)  # report the C of the mirrored problem
        # One-standard-error rule: the strongest regularisation whose held-out
        # error is within one standard error of the smallest (sparser, and as
        # good within the noise of the folds); or the smallest error itself.
        best = select_on_path(np.array([p.error for p in self.path_]),
                              np.array([p.error_std for p in self.path_]), len(folds),
                              self.selection)
        self.C_ = float(Cs[best])
        self.lambda_ = 1.0 / self.C_
        self.cv_error_ = self.path_[best].error
        # the folds' mean weights at the chosen C: where a screened fit of all pairs starts
        w = _fit_rows(learner, 2.0 * self.C_, Xs, labels, None, self.tol, self.max_iter, screen,
                      np.mean(fold_weights[best], axis=0))
        self.scale_ = scale
        self.coef_ = w / scale
        self.n_features_in_ = X.shape[1]
        return self

    def decision_function(self, X: np.ndarray) -> np.ndarray:
        """Reward w^T x of each candidate (Eq. 1), (n, d) -> (n,)."""
        check_is_fitted(self)
        X = np.asarray(X, dtype=np.float64)
        if X.ndim != 2 or X.shape[1] != self.n_features_in_:
            raise FootfallError(f"expected {self.n_features_in_} features, got shape {X.shape}")
        return X @ self.coef_

    def score(self, X: np.ndarray, y: np.ndarray, groups: np.ndarray) -> float:
        """Top-1 agreement: the fraction of demonstrations whose chosen candidate ranks first."""
        X, y, groups = np.asarray(X, dtype=np.float64), np.asarray(y), np.asarray(groups)
        _check_demonstrations(X, y, groups)
        r = self.decision_function(X)
        uniq, inverse = np.unique(groups, return_inverse=True)
        best = np.full(uniq.size, -np.inf)
        np.maximum.at(best, inverse, r)
        chosen = chosen_rows(y, groups)
        return float(np.mean(r[chosen] >= best[inverse[chosen]]))
