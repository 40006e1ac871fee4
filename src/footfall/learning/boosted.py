"""A gradient-boosted ranker: LightGBM's ``lambdarank`` with each demonstration as one query.

Each demonstration is one query group whose chosen candidate is the one
relevant item; LightGBM fits regression trees to the LambdaRank gradients
(NDCG of the chosen candidate). The number of trees is chosen by
cross-validation with grouped folds -- the held-out pairwise error (the
linear learners' measure) at each point of :data:`TREE_PATH` -- and the
linear learners' selection rules (``1se``: the fewest trees within one
standard error of the smallest error). Columns no tree splits on are dropped
(a template no tree reads is not kept), so the boosted function selects
templates too.

The model file holds the trees as checked arrays (:class:`Forest`), not
LightGBM's text format: LightGBM and XGBoost both crash the process (abort,
segmentation fault) on some corrupted model texts, and a model file is input.
The arrays are evaluated here, vectorised over trees and candidates, and the
tests check that they give LightGBM's own predictions.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numba
import numpy as np
from sklearn.base import BaseEstimator
from sklearn.utils.validation import check_is_fitted

from footfall.core.errors import FootfallError
from footfall.core.validate import require_float_array, require_number
from footfall.features.family import FeatureFamily
from footfall.learning.function import MAX_WEIGHT, VETO_PENALTY, ColumnFunction, own_arrays
from footfall.learning.learner import Learner, register_learner
from footfall.learning.ranker import (
    PathPoint,
    _check_demonstrations,
    grouped_folds,
    pairwise_error,
    select_on_path,
    units_of,
)

TREE_PATH = (10, 25, 50, 100, 200, 400)  # numbers of trees cross-validated, simplest first
MAX_TREES = 100_000  # most trees a model file may hold
MAX_NODES = 10_000_000  # most tree nodes a model file may hold
FOREST_ARRAYS = ("feature", "threshold", "left", "right", "value", "roots")  # a forest's arrays


# ------------------------------------------------------------------ the forest as arrays
@dataclass(frozen=True, eq=False)
class Forest:
    """Regression trees as flat node arrays; a candidate's value is the sum of its leaves.

    Node k of the forest splits on column ``feature[k]``: a candidate x goes
    to node ``left[k]`` if x[feature[k]] <= ``threshold[k]``, else to
    ``right[k]``. A leaf has ``feature`` -1, children equal to itself and its
    value in ``value`` (an internal node's value is 0). ``roots`` (T,) are the
    trees' first nodes. Children come after their parent, so every path ends
    at a leaf within ``depth`` steps.
    """

    feature: np.ndarray  # (N,) int column index, -1 at a leaf
    threshold: np.ndarray  # (N,) split value [units of the column]
    left: np.ndarray  # (N,) int node index
    right: np.ndarray  # (N,) int node index
    value: np.ndarray  # (N,) leaf value [reward]
    roots: np.ndarray  # (T,) int node index
    depth: int  # longest root-to-leaf path [splits]

    def predict(self, X: np.ndarray) -> np.ndarray:
        """The sum over trees of each candidate's leaf value, (n, d) -> (n,): each candidate
        walked down each tree, its leaf values added tree by tree in the trees' order
        (compiled: :func:`_leaf_sums`); a candidate's value does not depend on the others."""
        X = np.ascontiguousarray(X, dtype=np.float64)
        if X.ndim != 2:
            raise FootfallError(f"a forest predicts from a (n, d) matrix, got shape {X.shape}")
        if self.roots.size == 0:
            return np.zeros(X.shape[0])
        return _leaf_sums(X, self.feature, self.threshold, self.left, self.right, self.value,
                          self.roots, self.depth)

    def used_columns(self, d: int) -> np.ndarray:
        """(d,) bool: the columns some split reads."""
        used = np.zeros(d, dtype=bool)
        used[self.feature[self.feature >= 0]] = True
        return used

    def renumbered(self, kept: np.ndarray) -> Forest:
        """The forest over the kept columns only (``kept`` (d,) bool must hold every used one)."""
        new = np.cumsum(kept) - 1
        feature = np.where(self.feature >= 0, new[np.maximum(self.feature, 0)], -1)
        return Forest(feature, self.threshold, self.left, self.right, self.value, self.roots,
                      self.depth)

    def arrays(self) -> dict[str, np.ndarray]:
        """The node arrays as float64 (integers exactly), for the model file."""
        return {k: np.asarray(getattr(self, k), dtype=np.float64) for k in FOREST_ARRAYS}

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray], n_columns: int, where: str) -> Forest:
        """A forest from :meth:`arrays`' output, every node checked (raise naming the array)."""
        got = {}
        for k in FOREST_ARRAYS:
            if k not in arrays:
                raise FootfallError(f"lacks array {where}{k}")
            got[k] = require_float_array(arrays[k], f"array {where}{k}", (None,),
                                         bound=MAX_WEIGHT)
        n, t = got["feature"].size, got["roots"].size
        if not 1 <= t <= MAX_TREES or not t <= n <= MAX_NODES:
            raise FootfallError(f"array {where}roots must hold 1 to {MAX_TREES} trees and "
                                f"{where}feature up to {MAX_NODES} nodes")
        for k in ("threshold", "left", "right", "value"):
            if got[k].size != n:
                raise FootfallError(f"array {where}{k} must have shape ({n},), one per node")
        ints = {}
        for k, low, high in (("feature", -1, n_columns - 1), ("left", 0, n - 1),
                             ("right", 0, n - 1), ("roots", 0, n - 1)):
            a = got[k]
            if np.any(a != np.round(a)) or np.any(a < low) or np.any(a > high):
                raise FootfallError(f"array {where}{k} must hold whole numbers in "
                                    f"[{low}, {high}]")
            ints[k] = a.astype(np.intp)
        idx = np.arange(n)
        leaf = ints["feature"] < 0
        if np.any(leaf & ((ints["left"] != idx) | (ints["right"] != idx))) or np.any(
                ~leaf & ((ints["left"] <= idx) | (ints["right"] <= idx))):
            raise FootfallError(f"arrays {where}left and {where}right must lead from each node "
                                f"to later ones (a leaf: to itself)")
        depth = _depth(ints["left"], ints["right"], leaf)
        return cls(ints["feature"], got["threshold"], ints["left"], ints["right"],
                   np.where(leaf, got["value"], 0.0), ints["roots"], depth)


@numba.njit(cache=True, nogil=True)
def _leaf_sums(X, feature, threshold, left, right, value, roots, depth):  # pragma: no cover
    """Each row of X (n, d)'s leaf values summed over the trees ``roots`` (T,) in their order,
    (n,): at node k a row goes left if ``X[row, feature[k]] <= threshold[k]``, else right
    (NaN: right), for at most ``depth`` splits; a leaf (feature -1) ends the walk. A tree at a
    time, all rows down it: independent walks the processor overlaps."""
    out = np.empty(X.shape[0])
    for t in range(roots.shape[0]):
        for i in range(X.shape[0]):
            node = roots[t]
            for _ in range(depth):
                f = feature[node]
                if f < 0:
                    break
                node = left[node] if X[i, f] <= threshold[node] else right[node]
            if t == 0:
                out[i] = value[node]
            else:
                out[i] += value[node]
    return out


def _depth(left: np.ndarray, right: np.ndarray, leaf: np.ndarray) -> int:
    """The longest path from any node to a leaf (children after parents: one backward pass
    per level, at most the number of nodes)."""
    depth = np.zeros(left.size, dtype=np.intp)
    while True:  # levels, not nodes: each pass is vectorised over every node
        new = np.where(leaf, 0, 1 + np.maximum(depth[left], depth[right]))
        if np.array_equal(new, depth):
            return int(depth.max(initial=0))
        depth = new


def forest_of(booster: Any) -> Forest:
    """The trees of a fitted LightGBM booster as a :class:`Forest`.

    Only numerical ``<=`` splits on finite columns are read (footfall's
    features are finite; LightGBM makes no other split on them).
    """
    feature, threshold, left, right, value, roots = [], [], [], [], [], []

    def add(node: dict) -> int:
        k = len(feature)
        feature.append(-1)
        threshold.append(0.0)
        left.append(k)
        right.append(k)
        value.append(float(node.get("leaf_value", 0.0)))
        if "split_feature" in node:
            if node.get("decision_type") != "<=" or node.get("missing_type") == "Zero":
                raise FootfallError("a boosted tree has a split footfall does not read "
                                    f"({node.get('decision_type')}, {node.get('missing_type')})")
            feature[k] = int(node["split_feature"])
            threshold[k] = float(node["threshold"])
            left[k] = add(node["left_child"])
            right[k] = add(node["right_child"])
        return k

    for tree in booster.dump_model()["tree_info"]:
        roots.append(add(tree["tree_structure"]))
    arrays = {"feature": np.array(feature, float), "threshold": np.array(threshold),
              "left": np.array(left, float), "right": np.array(right, float),
              "value": np.array(value), "roots": np.array(roots, float)}
    return Forest.from_arrays(arrays, booster.num_feature(), "forest.")


# ------------------------------------------------------------------ the estimator
class BoostedRanker(BaseEstimator):
    """A foothold ranking function: LightGBM trees fitted to LambdaRank gradients.

    Parameters
    ----------
    objective : {"lambdarank", "rank_xendcg"}
        LightGBM's ranking objective.
    trees : tuple of int
        Numbers of trees cross-validated (:data:`TREE_PATH`), increasing.
    num_leaves, learning_rate, min_data_in_leaf, feature_fraction, lambda_l2
        LightGBM's tree settings (leaves per tree, shrinkage, fewest candidates
        per leaf, share of columns drawn per tree, L2 penalty on leaf values).
    cv : int
        Folds, grouped by demonstration (or by the ``units`` given to :meth:`fit`).
    selection : {"1se", "min"}
        The number of trees: the fewest within one standard error of the
        smallest held-out error, or the smallest.
    random_state : int
        LightGBM's seed (column sampling); training is deterministic.
    n_jobs : int
        LightGBM's threads. One by default: footfall runs its work in parallel
        processes, and LightGBM's OpenMP threads on cores that other processes
        hold spin instead of working (400 trees on 160 candidates took 12.6 s
        with two threads on a busy two-core machine, 0.09 s with one; 100
        demonstrations of 100 candidates, 62 s against 18 s). The trees are
        the same whatever the number.

    The cross-validation folds are trained one after another, never in threads at once:
    LightGBM's ranking objectives keep their gain and discount tables in static members
    (``DCGCalculator``) that every new booster re-initialises, so two lambdarank boosters made
    in two threads race on them (measured: a segmentation fault in ``lib_lightgbm`` while a
    hind-leg function learned its folds two at a time).

    Attributes
    ----------
    forest_ : :class:`Forest`, the trees;  n_trees_ : int
    cv_error_ : float, the held-out pairwise error at ``n_trees_``
    feature_importances_ : (d,) float, each column's total split gain (0: no tree reads it)
    path_ : list of PathPoint (``C`` holds the number of trees)
    """

    def __init__(self, objective: str = "lambdarank", trees: tuple[int, ...] = TREE_PATH,
                 num_leaves: int = 7, learning_rate: float = 0.05, min_data_in_leaf: int = 50,
                 feature_fraction: float = 0.5, lambda_l2: float = 1.0, cv: int = 5,
                 selection: str = "1se", random_state: int = 0, n_jobs: int = 1):
        self.objective = objective
        self.trees = trees
        self.num_leaves = num_leaves
        self.learning_rate = learning_rate
        self.min_data_in_leaf = min_data_in_leaf
        self.feature_fraction = feature_fraction
        self.lambda_l2 = lambda_l2
        self.cv = cv
        self.selection = selection
        self.random_state = random_state
        self.n_jobs = n_jobs

    def _params(self) -> dict:
        return {"objective": self.objective, "num_leaves": int(self.num_leaves),
                "learning_rate": float(self.learning_rate),
                "min_data_in_leaf": int(self.min_data_in_leaf),
                "feature_fraction": float(self.feature_fraction),
                "lambda_l2": float(self.lambda_l2), "seed": int(self.random_state),
                "num_threads": int(self.n_jobs),
                "deterministic": True, "force_col_wise": True, "verbosity": -1}

    def _dataset(self, X: np.ndarray, y: np.ndarray, sizes: np.ndarray) -> Any:
        """LightGBM's binned data of ``X``, built at once with the training parameters: it
        keeps no reference to ``X``, so a fold's copy of the rows is freed before its trees
        are grown (at 1 600 demonstrations each copy is over a gigabyte)."""
        import lightgbm  # imported when boosting: the linear learners do without it

        return lightgbm.Dataset(X, y, group=sizes, params=self._params(),
                                free_raw_data=True).construct()

    def _train(self, data: Any, rounds: int) -> Any:
        import lightgbm

        return lightgbm.train(self._params(), data, num_boost_round=int(rounds))

    def fit(self, X: np.ndarray, y: np.ndarray, groups: np.ndarray,
            units: np.ndarray | None = None) -> BoostedRanker:
        """Learn from stacked candidates of demonstrations (as :class:`FootholdRanker`)."""
        X = np.asarray(X, dtype=np.float64)
        y, groups = np.asarray(y), np.asarray(groups)
        _check_demonstrations(X, y, groups)
        if self.objective not in ("lambdarank", "rank_xendcg"):
            raise FootfallError(f"unknown ranking objective {self.objective!r}")
        trees = np.asarray(self.trees, dtype=int)
        if trees.size == 0 or np.any(trees < 1) or np.any(np.diff(trees) <= 0):
            raise FootfallError("trees must be increasing positive numbers")
        if int(self.cv) < 2:
            raise FootfallError("cv needs at least 2 folds")
        if int(self.n_jobs) < 1:
            raise FootfallError(f"n_jobs must be at least 1 thread, got {self.n_jobs}")
        if np.any(np.diff(groups) < 0):  # LightGBM reads queries as contiguous runs (stack's
            order = np.argsort(groups, kind="stable")  # are: no copy of X then)
            X, y, groups = X[order], y[order], groups[order]
            units = None if units is None else np.asarray(units)[order]
        uniq, sizes = np.unique(groups, return_counts=True)
        folds = grouped_folds(uniq, int(self.cv), units_of(groups, units, uniq))

        def fold_errors(fold: tuple[np.ndarray, np.ndarray]) -> list[float]:
            train = np.isin(groups, uniq[fold[0]])
            booster = self._train(self._dataset(X[train], y[train], sizes[fold[0]]), trees[-1])
            test = ~train
            return [pairwise_error(booster.predict(X[test], num_iteration=int(t)), y[test],
                                   groups[test]) for t in trees]

        errors = np.array([fold_errors(f) for f in folds])  # one at a time: see the class
        self.path_ = [PathPoint(float(t), float(errors[:, j].mean()), float(errors[:, j].std()),
                                float("nan"), float(t)) for j, t in enumerate(trees)]
        best = select_on_path(errors.mean(axis=0), errors.std(axis=0), len(folds),
                              self.selection)
        self.n_trees_ = int(trees[best])
        self.cv_error_ = float(errors[:, best].mean())
        booster = self._train(self._dataset(X, y, sizes), self.n_trees_)
        self.forest_ = forest_of(booster)
        self.feature_importances_ = np.asarray(booster.feature_importance("gain"), dtype=float)
        self.n_features_in_ = X.shape[1]
        return self

    def decision_function(self, X: np.ndarray) -> np.ndarray:
        """The forest's value of each candidate, (n, d) -> (n,)."""
        check_is_fitted(self)
        return self.forest_.predict(X)


# ------------------------------------------------------------------ the function and learner
@dataclass(frozen=True, eq=False)
class BoostedFunction(ColumnFunction):
    """A sum of regression trees over the families' kept columns: the boosted ranker's function."""

    families: tuple[FeatureFamily, ...]
    forest: Forest
    info: dict = field(default_factory=dict)  # trees, cv error, path, the families' facts
    veto: Forest | None = None  # a learned veto (footfall.learning.veto): trees of the log-odds
    # that the teacher refuses a candidate outright (> 0: refused), or with ``veto_margin`` of
    # the values its refusals are relative to; a refused candidate loses VETO_PENALTY
    veto_margin: float | None = None  # [value units] a relative veto refuses a candidate
    # valued more than this below the best of its candidate set; None: the log-odds veto

    def __post_init__(self) -> None:
        for forest in (self.forest, self.veto):
            if forest is not None and forest.feature.size and \
                    forest.feature.max(initial=-1) >= self.n_columns:
                raise FootfallError("a boosted tree reads a column its families do not have")

    def predict(self, X: np.ndarray) -> np.ndarray:
        """The sum of the trees' leaf values, (n, d) -> (n,), less VETO_PENALTY where the veto
        refuses a candidate (its log-odds above 0)."""
        value = self.forest.predict(X)
        if self.veto is None or self.veto_margin is not None:
            return value
        return value - VETO_PENALTY * (self.veto.predict(X) > 0.0)

    def refused_in_sets(self, X: np.ndarray, which: np.ndarray) -> np.ndarray | None:
        """With a relative veto: the rows whose predicted judged value lies more than
        ``veto_margin`` below the best of their set (``which``)."""
        if self.veto is None or self.veto_margin is None:
            return None
        judged = self.veto.predict(X)
        which = np.asarray(which, dtype=np.intp)
        best = np.full(int(which.max(initial=-1)) + 1, -np.inf)
        np.maximum.at(best, which, judged)
        return best[which] - judged > self.veto_margin

    def without_veto(self) -> BoostedFunction:
        """The ranker alone (itself without a veto)."""
        return self if self.veto is None else replace(self, veto=None, veto_margin=None)

    def arrays(self) -> dict[str, np.ndarray]:
        """``boosted.feature``, ``.threshold``, ``.left``, ``.right``, ``.value``, ``.roots``;
        with a veto, its forest's as ``boosted.veto.*``."""
        out = {f"boosted.{k}": v for k, v in self.forest.arrays().items()}
        if self.veto is not None:
            out.update({f"boosted.veto.{k}": v for k, v in self.veto.arrays().items()})
        if self.veto_margin is not None:
            out["boosted.veto_margin"] = np.array([self.veto_margin])
        return out

    @classmethod
    def from_arrays(cls, families: tuple[FeatureFamily, ...], arrays: dict[str, np.ndarray],
                    info: dict, prefix: str = "") -> BoostedFunction:
        d = sum(len(f.columns()) for f in families)
        arrays = dict(arrays)
        veto_prefix, margin_key = f"{prefix}boosted.veto.", f"{prefix}boosted.veto_margin"
        margin = arrays.pop(margin_key, None)
        veto = None
        if any(k.startswith(veto_prefix) for k in arrays):
            veto = Forest.from_arrays(own_arrays({k: v for k, v in arrays.items()
                                                  if k.startswith(veto_prefix)},
                                                 veto_prefix, FOREST_ARRAYS), d, veto_prefix)
        if margin is not None:
            if veto is None:
                raise FootfallError(f"array {margin_key} without a veto's trees")
            margin = require_number(require_float_array(margin, f"array {margin_key}", (1,))[0],
                                    f"array {margin_key}", 0.0, MAX_WEIGHT)
        mine = own_arrays({k: v for k, v in arrays.items() if not k.startswith(veto_prefix)},
                          f"{prefix}boosted.", FOREST_ARRAYS)
        return cls(tuple(families), Forest.from_arrays(mine, d, f"{prefix}boosted."), info, veto,
                   margin)


@dataclass(frozen=True)
class BoostedLearner(Learner):
    """The boosted ranker as a registered learner (``--learner lambdarank``)."""

    name: str = "lambdarank"
    description: str = ("gradient-boosted trees (LightGBM lambdarank, one query per "
                        "demonstration): non-linear, keeps the columns its trees read")
    function_type: type = BoostedFunction
    ranks_columns: bool = True
    order_only: bool = True  # a split reads a column's order: an RBF bandwidth re-maps nothing
    objective: str = "lambdarank"
    vetoes: bool = True  # its function can carry a learned veto (footfall.learning.veto)
    threads: int = 1  # LightGBM's threads a fit (see BoostedRanker's n_jobs)

    def fit(self, X, y, groups, *, Cs=10, cv: int = 5, selection: str = "1se",
            units=None) -> BoostedRanker:
        """:class:`BoostedRanker`, fitted (the number of trees is its path; ``Cs`` unused)."""
        return BoostedRanker(self.objective, cv=cv, selection=selection,
                             n_jobs=self.threads).fit(X, y, groups, units)

    def function(self, fitted: BoostedRanker, families: tuple[FeatureFamily, ...],
                 n_demonstrations: int, veto: Forest | None = None,
                 veto_margin: float | None = None) -> BoostedFunction:
        """Per family the columns a tree reads (a template library keeps those templates);
        with a ``veto`` over the same columns (:func:`footfall.learning.veto.fit_veto`), the
        columns either reads."""
        used = fitted.forest_.used_columns(fitted.n_features_in_)
        if veto is not None:
            used |= veto.used_columns(fitted.n_features_in_)
        kept, masks, info = [], [], {}
        start = 0
        for family in families:
            stop = start + len(family.columns())
            reduced, keep = family.select(used[start:stop])
            kept.append(reduced)
            masks.append(keep)
            info.update(reduced.info())
            start = stop
        info.update({"trees": fitted.n_trees_, "cv_error": fitted.cv_error_,
                     "path": [vars(p) for p in fitted.path_],
                     "n_demonstrations": n_demonstrations, "objective": self.objective,
                     "n_nonzero": int(np.count_nonzero(used))})
        keep = np.concatenate(masks)
        return BoostedFunction(tuple(kept), fitted.forest_.renumbered(keep), info,
                               None if veto is None else veto.renumbered(keep), veto_margin)

    def importance(self, fitted: BoostedRanker) -> np.ndarray:
        """Each column's total split gain in the trees (LightGBM's "gain" importance)."""
        return fitted.feature_importances_


register_learner(BoostedLearner())
