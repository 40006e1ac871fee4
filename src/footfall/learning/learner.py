"""What a learner is: the extension point through which ranking learners plug in.

A learner learns a ranking function of one leg group from the stacked
feature matrices of demonstrations (paper §II-C): :meth:`Learner.fit` returns
a fitted scikit-learn estimator, and :meth:`Learner.function` turns it into a
:class:`~footfall.learning.function.RankingFunction` -- which families and
columns it keeps, and its own arrays for the model file. The built-in
learners are linear classifiers on pairwise differences
(:mod:`footfall.learning.ranker`), a kernel ranker on random Fourier features
(:mod:`footfall.learning.kernel`) and a gradient-boosted ranker
(:mod:`footfall.learning.boosted`); a new ranker is one new module with a
:class:`~footfall.learning.function.RankingFunction` of its own and a
``register_learner`` call.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import fields, is_dataclass, replace
from typing import Any

import numpy as np

from footfall.core.registry import Registry
from footfall.features.family import FeatureFamily
from footfall.learning.function import RankingFunction


class Learner(ABC):
    """A ranking learner: the registry's entry.

    Attributes ``name`` (the registry key, ``footfall learn --learner``),
    ``description`` (one line for --help and reports) and ``function_type``
    (the :class:`RankingFunction` class it makes, which reads its arrays back
    from a model file); ``ranks_columns``: whether :meth:`importance` says how
    much a fit relies on each column (needed to keep to a template budget);
    ``order_only``: whether a fit depends on each column only through the
    order of its values (regression trees), so that a family's hyperparameter
    which re-maps a column monotonically -- an RBF bandwidth -- changes nothing
    it could learn and is not searched for it
    (:meth:`FeatureFamily.tune <footfall.features.family.FeatureFamily.tune>`); ``vetoes``:
    whether :meth:`function` takes a learned veto (``veto=``, :mod:`footfall.learning.veto`);
    ``threads``: the threads a fit may use where the learner has its own (the boosted ranker's
    LightGBM), the fit the same whatever the number (``dataclasses.replace`` sets it).
    """

    name: str
    description: str
    function_type: type[RankingFunction]
    ranks_columns: bool = False  # its importance() ranks the columns (a template budget works)
    order_only: bool = False  # it reads each column's order only: monotone re-maps are not tuned
    vetoes: bool = False  # its function can carry a learned veto (footfall.learning.veto)
    threads: int = 1  # threads a fit may use, where the learner has its own

    def with_threads(self, threads: int) -> Learner:
        """This learner with ``threads`` where it has threads of its own (a dataclass field
        ``threads``), else itself."""
        if (threads != self.threads and is_dataclass(self)
                and "threads" in {f.name for f in fields(self)}):
            return replace(self, threads=threads)
        return self

    @abstractmethod
    def fit(self, X: np.ndarray, y: np.ndarray, groups: np.ndarray, *, Cs: Any = 10,
            cv: int = 5, selection: str = "1se", units: np.ndarray | None = None) -> Any:
        """A fitted estimator for stacked candidates of demonstrations.

        Parameters
        ----------
        X : array of shape (n_candidates, n_features)
            Features of the candidates of all demonstrations, stacked.
        y : array of shape (n_candidates,)
            Relevance levels, whole numbers: 1 for the chosen candidate of its
            demonstration and 0 for the others, or graded by a teacher's verdict
            (:mod:`footfall.learning.supervision`), the chosen candidate alone at its
            demonstration's highest level.
        groups : array of shape (n_candidates,)
            The demonstration each candidate belongs to (cross-validation
            folds never split one).
        Cs, cv, selection
            The regularisation path, folds and selection rule, for learners
            that use them.
        units : array of shape (n_candidates,), optional
            The fold unit of each candidate's demonstration (its run or
            board): cross-validation folds never split one. None: each
            demonstration is its own unit.

        Returns
        -------
        estimator
            With ``decision_function(X) -> (n,)`` (higher: preferred) and
            ``cv_error_``, its held-out pairwise error (the families tune their
            hyperparameters, e.g. the RBF bandwidths, by it).
        """

    @abstractmethod
    def function(self, fitted: Any, families: tuple[FeatureFamily, ...],
                 n_demonstrations: int) -> RankingFunction:
        """The fitted estimator as a ranking function over ``families`` (whose columns are
        ``X``'s, in order); a sparse learner drops the columns it left at zero
        (:meth:`FeatureFamily.select <footfall.features.family.FeatureFamily.select>`)."""

    def importance(self, fitted: Any) -> np.ndarray | None:
        """How much the fitted estimator relies on each column, (d,) >= 0 (0: a column it does
        not read), or None if it cannot say (a template budget then cannot be met)."""
        return None


LEARNERS: Registry[Learner] = Registry("learner")  # every registered learner, by name


def register_learner(learner: Learner) -> Learner:
    """Make a learner available by its name (the CLI's ``--learner`` choices come from here)."""
    return LEARNERS.register(learner.name, learner)


def get_learner(name: str) -> Learner:
    """The registered learner called ``name`` (plugins included: :mod:`footfall.core.plugins`)."""
    return LEARNERS.get(name)
