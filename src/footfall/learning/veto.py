"""A learned veto: which candidates the teacher refuses outright, learned beside the ranker.

A teacher with a veto -- the reproduction's ``accepted`` teacher: the hand-tuned reward among
the footholds the synthetic expert accepts -- chooses in two steps: first it refuses some
candidates ("never here"), then it ranks the rest. A ranker learned from its levels
(:mod:`footfall.learning.supervision`) learns the order, but a ranking loss cares about the
top of the list: a refused candidate ranked second costs it little, and the footstep planner,
trading a foothold's value against its path bias and the next steps, often takes the second.
The veto is the student's copy of the first step, on the ranker's columns, in one of two
forms; a candidate it refuses loses :data:`~footfall.learning.function.VETO_PENALTY`
(:class:`~footfall.learning.boosted.BoostedFunction`):

* **relative**, where the demonstrations carry the values the teacher's refusals are relative
  to (``judged``: the synthetic expert's values behind the guarded teacher's veto): trees of
  those values (LightGBM, squared error, each value clipped at :data:`JUDGED_CLIP` below the
  best of its F, far from where the refusal is decided), and the teacher's margin read off the
  demonstrations (the largest shortfall it accepted). Scoring a candidate set, a candidate
  predicted more than the margin below the set's best is refused -- the teacher's own rule, so
  that in a place where every foothold is poor the least poor still stand;
* **absolute**, from refusals alone (a person's marks): trees of the log-odds that the teacher
  refuses a candidate (binary log-loss); log-odds above 0 (refused more likely than not) is
  refused.

The number of trees is chosen on :data:`~footfall.learning.boosted.TREE_PATH` by
cross-validated squared error (relative) or classification error (absolute) with the ranker's
folds (a demonstration, or its run or board, is never split).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError
from footfall.learning.boosted import TREE_PATH, Forest, forest_of
from footfall.learning.ranker import grouped_folds, select_on_path, units_of

JUDGED_CLIP = 20.0  # [value units] a judged value counts at most this far below the best of its
# F (or three margins, if more): the veto decides at the margin, a few units; beyond twice the
# severe shortfall the exact value does not matter
VETO_PARAMS = {"objective": "binary", "num_leaves": 7, "learning_rate": 0.05,
               "min_data_in_leaf": 50, "feature_fraction": 0.5, "lambda_l2": 1.0,
               "num_threads": 1, "deterministic": True, "force_col_wise": True,
               "verbosity": -1}  # the boosted ranker's tree settings, for a binary log-loss


@dataclass(frozen=True)
class Veto:
    """A fitted veto: its trees over the columns it was fitted on, and how it was chosen."""

    forest: Forest  # the judged values [value units] (relative), or the log-odds that the
    # teacher refuses a candidate (absolute: > 0 refused)
    trees: int  # trees chosen
    cv_error: float  # held-out mean squared error [value units^2] (relative), or share of
    # candidates classified wrongly (absolute), at ``trees``
    refused_share: float  # share of the training candidates the teacher refused
    margin: float | None = None  # [value units] relative: refused more than this below the best

    def info(self) -> dict[str, Any]:
        """Plain figures for a function's record."""
        return {"veto_trees": self.trees, "veto_cv_error": self.cv_error,
                "veto_refused_share": self.refused_share, "veto_margin": self.margin}


def _train(X: np.ndarray, target: np.ndarray, rounds: int, seed: int, objective: str,
           threads: int) -> Any:
    import lightgbm  # imported when a veto is learned

    params = {**VETO_PARAMS, "seed": seed, "objective": objective, "num_threads": int(threads)}
    data = lightgbm.Dataset(X, target.astype(np.float64), params=params,
                            free_raw_data=True).construct()
    return lightgbm.train(params, data, num_boost_round=int(rounds))


def fit_veto(X: np.ndarray, refused: np.ndarray, groups: np.ndarray, *, cv: int = 5,
             selection: str = "min", units: np.ndarray | None = None, seed: int = 0,
             judged: np.ndarray | None = None, shortfall: np.ndarray | None = None,
             threads: int = 1) -> Veto:
    """The veto learned from candidates (n, d) and the teacher's refusals (n,) bool: relative
    with ``judged`` (n,) [value units] and each candidate's ``shortfall`` (n,) [value units]
    below the best judged value of its whole F, absolute without them.

    ``groups`` (n,) names each candidate's demonstration and ``units`` (n,), if given, its fold
    unit (run or board): no fold splits one. The folds are fitted one after another (LightGBM's
    objectives keep static state that boosters made at once in threads race on), each with
    LightGBM's ``threads`` (the same trees whatever the number).

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
    if judged is None:
        target, objective, margin = refused.astype(np.float64), "binary", None
    else:
        shortfall = np.asarray(shortfall, dtype=np.float64)
        margin = float(shortfall[~refused].max())
        clip = max(JUDGED_CLIP, 3.0 * margin)  # well beyond where the veto decides
        target = np.asarray(judged, dtype=np.float64) + np.maximum(shortfall - clip, 0.0)
        objective = "regression"
    trees, errors = _path(X, target, refused, groups, units, int(cv), objective, seed, threads)
    best = select_on_path(errors.mean(axis=0), errors.std(axis=0), errors.shape[0], selection)
    booster = _train(X, target, trees[best], seed, objective, threads)
    return Veto(forest_of(booster), int(trees[best]), float(errors[:, best].mean()),
                float(refused.mean()), margin)


def _path(X: np.ndarray, target: np.ndarray, refused: np.ndarray, groups: np.ndarray,
          units: np.ndarray | None, cv: int, objective: str, seed: int, threads: int
          ) -> tuple[np.ndarray, np.ndarray]:
    """The numbers of trees and each fold's held-out error at each, (folds, trees): squared
    error of a regression, the share misclassified of the log-odds."""
    uniq = np.unique(groups)
    folds = grouped_folds(uniq, cv, units_of(groups, units, uniq))
    trees = np.asarray(TREE_PATH)
    errors = np.empty((len(folds), trees.size))
    for k, (train_groups, _) in enumerate(folds):  # one at a time: see fit_veto
        train = np.isin(groups, uniq[train_groups])
        booster = _train(X[train], target[train], trees[-1], seed, objective, threads)
        for j, t in enumerate(trees):
            raw = booster.predict(X[~train], num_iteration=int(t), raw_score=True)
            errors[k, j] = (np.mean((raw - target[~train]) ** 2) if objective == "regression"
                            else np.mean((raw > 0.0) != refused[~train]))
    return trees, errors
