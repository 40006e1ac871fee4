"""A learned veto: which candidates the teacher refuses outright, learned beside the ranker.

A teacher with a veto -- the reproduction's ``accepted`` teacher: the hand-tuned reward among
the footholds the synthetic expert accepts -- chooses in two steps: first it refuses some
candidates ("never here"), then it ranks the rest. A ranker learned from its levels
(:mod:`footfall.learning.supervision`) learns the order, but a ranking loss cares about the
top of the list: a refused candidate ranked second costs it little, and the footstep planner,
trading a foothold's value against its path bias and the next steps, often takes the second.
The veto is the student's copy of the first step: gradient-boosted trees (LightGBM, binary
log-loss) of the log-odds that the teacher refuses a candidate, from every candidate of the
demonstrations that carry refusals, on the ranker's columns; a candidate with log-odds above
0 (refused more likely than not) loses :data:`~footfall.learning.function.VETO_PENALTY`
(:class:`~footfall.learning.boosted.BoostedFunction`). The number of trees is chosen on
:data:`~footfall.learning.boosted.TREE_PATH` by cross-validated classification error with
the ranker's folds (a demonstration, or its run or board, is never split).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError
from footfall.learning.boosted import TREE_PATH, Forest, forest_of
from footfall.learning.ranker import grouped_folds, select_on_path, units_of

VETO_PARAMS = {"objective": "binary", "num_leaves": 7, "learning_rate": 0.05,
               "min_data_in_leaf": 50, "feature_fraction": 0.5, "lambda_l2": 1.0,
               "num_threads": 1, "deterministic": True, "force_col_wise": True,
               "verbosity": -1}  # the boosted ranker's tree settings, for a binary log-loss


@dataclass(frozen=True)
class Veto:
    """A fitted veto: its trees over the columns it was fitted on, and how it was chosen."""

    forest: Forest  # log-odds that the teacher refuses a candidate (> 0: refused)
    trees: int  # trees chosen
    cv_error: float  # held-out share of candidates classified wrongly at ``trees``
    refused_share: float  # share of the training candidates the teacher refused

    def info(self) -> dict[str, Any]:
        """Plain figures for a function's record."""
        return {"veto_trees": self.trees, "veto_cv_error": self.cv_error,
                "veto_refused_share": self.refused_share}


def _train(X: np.ndarray, refused: np.ndarray, rounds: int, seed: int) -> Any:
    import lightgbm  # imported when a veto is learned

    data = lightgbm.Dataset(X, refused.astype(np.float64), params={**VETO_PARAMS, "seed": seed},
                            free_raw_data=True).construct()
    return lightgbm.train({**VETO_PARAMS, "seed": seed}, data, num_boost_round=int(rounds))


def fit_veto(X: np.ndarray, refused: np.ndarray, groups: np.ndarray, *, cv: int = 5,
             selection: str = "min", units: np.ndarray | None = None, seed: int = 0) -> Veto:
    """The veto learned from candidates (n, d) and the teacher's refusals (n,) bool.

    ``groups`` (n,) names each candidate's demonstration and ``units`` (n,), if given, its fold
    unit (run or board): no fold splits one. The folds are fitted one after another (LightGBM's
    objectives keep static state that boosters made at once in threads race on).

    Raises
    ------
    FootfallError
        For shapes that do not agree, non-finite features, fewer fold units than folds, or
        refusals of only one kind (all refused or none: nothing to tell apart).
    """
    X = np.ascontiguousarray(X, dtype=np.float64)
    refused = np.asarray(refused, dtype=bool)
    groups = np.asarray(groups)
    if X.ndim != 2 or refused.shape != (X.shape[0],) or groups.shape != (X.shape[0],):
        raise FootfallError("a veto needs X (n, d), refused (n,) and groups (n,) of one length")
    if not np.isfinite(X).all():
        raise FootfallError("features contain NaN or infinite values")
    if refused.all() or not refused.any():
        raise FootfallError("a veto needs refused and accepted candidates both; the teacher's "
                            f"verdicts refuse {'every' if refused.all() else 'no'} candidate")
    uniq = np.unique(groups)
    folds = grouped_folds(uniq, int(cv), units_of(groups, units, uniq))
    trees = np.asarray(TREE_PATH)
    errors = np.empty((len(folds), trees.size))
    for k, (train_groups, _) in enumerate(folds):  # one at a time: see the docstring
        train = np.isin(groups, uniq[train_groups])
        booster = _train(X[train], refused[train], trees[-1], seed)
        for j, t in enumerate(trees):
            raw = booster.predict(X[~train], num_iteration=int(t), raw_score=True)
            errors[k, j] = np.mean((raw > 0.0) != refused[~train])
    best = select_on_path(errors.mean(axis=0), errors.std(axis=0), len(folds), selection)
    booster = _train(X, refused, trees[best], seed)
    return Veto(forest_of(booster), int(trees[best]), float(errors[:, best].mean()),
                float(refused.mean()))
