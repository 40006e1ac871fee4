"""A kernel ranker: pairwise logistic regression on random Fourier features (non-linear).

Each candidate's features, standardised, are mapped to random Fourier
features phi(x) = sqrt(2 / D) cos(W^T x + b) (scikit-learn's ``RBFSampler``,
an approximation of the RBF kernel exp(-gamma |x - x'|^2)), and the paper's
pairwise loss (Eq. 3, 5 with an L2 penalty) is fitted on differences of those
maps. The ranking function w^T phi(x) can prefer a middling value of a
feature, which w^T x cannot. Standardised columns are clipped to +-3 standard
deviations before the map (:func:`fourier_features`). The kernel width is relative to the number of
columns d: gamma = ``gamma_scale`` / d, so that two candidates one standard
deviation apart in every column have kernel exp(-gamma_scale). C = 1 / lambda
is chosen on a path by cross-validation with grouped folds and the same
selection rules as the linear learners. The model file holds the
standardisation, W, b and the weights as arrays, never a pickle.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.exceptions import ConvergenceWarning
from sklearn.kernel_approximation import RBFSampler
from sklearn.linear_model import LogisticRegression
from sklearn.utils.validation import check_is_fitted

from footfall.core.errors import FootfallError
from footfall.core.validate import require_float_array
from footfall.features.family import FeatureFamily
from footfall.learning.function import MAX_WEIGHT, ColumnFunction, own_arrays
from footfall.learning.learner import Learner, register_learner
from footfall.learning.ranker import (
    PathPoint,
    _check_demonstrations,
    grouped_folds,
    pairwise_transform,
    select_on_path,
    units_of,
)

KERNEL_LOG_C = (-3.0, 2.0)  # log10 of the smallest and largest C on the kernel ranker's path
CLIP = 3.0  # [standard deviations] standardised columns are clipped to +-CLIP before the map


def fourier_features(X: np.ndarray, mean: np.ndarray, scale: np.ndarray, projection: np.ndarray,
                     offset: np.ndarray) -> np.ndarray:
    """Random Fourier features (n, D) of raw features X (n, d): RBFSampler's map, from arrays.

    The standardised columns are clipped to +-:data:`CLIP` first: a template's RBF
    similarity is near 0 for most training candidates, so a foothold on new terrain that
    matches it well lies hundreds of standard deviations out, where the cosines are noise
    (measured: a kernel ranker that ranked its training decisions at percentile 0.97 ranked
    held-out ones at 0.49 without the clip).
    """
    z = np.clip((X - mean) / scale, -CLIP, CLIP) @ projection + offset
    return np.cos(z) * np.sqrt(2.0 / projection.shape[1])


class KernelRanker(BaseEstimator):
    """A foothold ranking function w^T phi(x) learned from demonstrations.

    Parameters
    ----------
    n_components : int
        D, the number of random Fourier features.
    gamma_scale : float
        The RBF kernel's gamma times the number of columns d (on standardised columns).
    Cs : int or array-like
        C values (1 / lambda) to cross-validate, or how many log-spaced ones over
        :data:`KERNEL_LOG_C`.
    cv : int
        Folds, grouped by demonstration (or by the ``units`` given to :meth:`fit`).
    selection : {"1se", "min"}
        Lambda as for the linear learners (:func:`~footfall.learning.ranker.select_on_path`).
    random_state : int
        Seed of the random projection.

    Attributes
    ----------
    mean_, scale_ : arrays (d,), the standardisation of the columns
    projection_ : array (d, D), W;  offset_ : array (D,), b [rad]
    coef_ : array (D,), the weights w
    C_, lambda_, cv_error_, path_ : as :class:`~footfall.learning.ranker.FootholdRanker`
    """

    def __init__(self, n_components: int = 300, gamma_scale: float = 1.0, Cs=6, cv: int = 5,
                 selection: str = "1se", random_state: int = 0, max_iter: int = 500):
        self.n_components = n_components
        self.gamma_scale = gamma_scale
        self.Cs = Cs
        self.cv = cv
        self.selection = selection
        self.random_state = random_state
        self.max_iter = max_iter

    def _weights(self, C: float, pairs: np.ndarray, labels: np.ndarray) -> np.ndarray:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            fit = LogisticRegression(C=C, fit_intercept=False, max_iter=self.max_iter,
                                     tol=1e-4).fit(pairs, labels)
        return fit.coef_.ravel().copy()

    def fit(self, X: np.ndarray, y: np.ndarray, groups: np.ndarray,
            units: np.ndarray | None = None) -> KernelRanker:
        """Learn from stacked candidates of demonstrations (as :class:`FootholdRanker`)."""
        X = np.asarray(X, dtype=np.float64)
        if int(self.cv) < 2:
            raise FootfallError("cv needs at least 2 folds")
        if int(self.n_components) < 1 or not float(self.gamma_scale) > 0:
            raise FootfallError("n_components must be at least 1 and gamma_scale positive")
        _check_demonstrations(X, np.asarray(y), np.asarray(groups))
        self.mean_ = X.mean(axis=0)
        scale = X.std(axis=0)
        self.scale_ = np.where(scale > 1e-12, scale, 1.0)
        d = X.shape[1]
        sampler = RBFSampler(gamma=float(self.gamma_scale) / d,
                             n_components=int(self.n_components),
                             random_state=self.random_state).fit(np.zeros((1, d)))
        self.projection_ = sampler.random_weights_.astype(np.float64)
        self.offset_ = sampler.random_offset_.astype(np.float64)
        phi = self.transform(X)
        pairs, _, pair_groups = pairwise_transform(phi, y, groups, mirrored=False)
        # As for the linear learners: alternate signs give two classes, no mirrored copies.
        signs = np.where(np.arange(pairs.shape[0]) % 2 == 0, 1.0, -1.0)
        pairs *= signs[:, None]
        Cs = (np.logspace(*KERNEL_LOG_C, int(self.Cs)) if np.isscalar(self.Cs)
              else np.sort(np.asarray(self.Cs, dtype=np.float64)))
        if Cs.size == 0 or not (np.isfinite(Cs) & (Cs > 0)).all():
            raise FootfallError("Cs must be finite and positive")
        folds = grouped_folds(pair_groups, int(self.cv), units_of(groups, units, pair_groups))
        self.path_ = []
        for C in Cs:  # strong to weak regularisation
            errors, losses = [], []
            for train, test in folds:
                w = self._weights(C, pairs[train], signs[train])
                margin = signs[test] * (pairs[test] @ w)
                errors.append(float(np.mean(margin <= 0)))
                losses.append(float(np.mean(np.logaddexp(0.0, -margin))))
            self.path_.append(PathPoint(float(C), float(np.mean(errors)), float(np.std(errors)),
                                        float(np.mean(losses)), float(self.n_components)))
        best = select_on_path(np.array([p.error for p in self.path_]),
                              np.array([p.error_std for p in self.path_]), len(folds),
                              self.selection)
        self.C_ = float(Cs[best])
        self.lambda_ = 1.0 / self.C_
        self.cv_error_ = self.path_[best].error
        self.coef_ = self._weights(self.C_, pairs, signs)
        self.n_features_in_ = d
        return self

    def transform(self, X: np.ndarray) -> np.ndarray:
        """phi(X) (n, D)."""
        return fourier_features(np.asarray(X, dtype=np.float64), self.mean_, self.scale_,
                                self.projection_, self.offset_)

    def decision_function(self, X: np.ndarray) -> np.ndarray:
        """w^T phi(x) of each candidate, (n, d) -> (n,)."""
        check_is_fitted(self)
        return self.transform(X) @ self.coef_


_ARRAYS = ("mean", "scale", "projection", "offset", "weights")


@dataclass(frozen=True, eq=False)
class KernelFunction(ColumnFunction):
    """w^T phi(x) over the families' columns: the kernel ranker's function."""

    families: tuple[FeatureFamily, ...]
    mean: np.ndarray  # (d,) column means [units of each column]
    scale: np.ndarray  # (d,) column standard deviations [units of each column]
    projection: np.ndarray  # (d, D) random weights W [1 / standard deviation]
    offset: np.ndarray  # (D,) random offsets b [rad]
    weights: np.ndarray  # (D,) w [reward per unit of phi]
    info: dict = field(default_factory=dict)  # lambda, C, cv error, path, gamma, the families' facts

    def __post_init__(self) -> None:
        d, D = self.n_columns, self.offset.shape[0]
        shapes = {"mean": (d,), "scale": (d,), "projection": (d, D), "weights": (D,)}
        for name, shape in shapes.items():
            if np.shape(getattr(self, name)) != shape:
                raise FootfallError(f"kernel function's {name} must have shape {shape}")

    def predict(self, X: np.ndarray) -> np.ndarray:
        """w^T phi(x), (n, d) -> (n,)."""
        return fourier_features(X, self.mean, self.scale, self.projection, self.offset) @ \
            self.weights

    def arrays(self) -> dict[str, np.ndarray]:
        """``kernel.mean``, ``kernel.scale``, ``kernel.projection``, ``kernel.offset``,
        ``kernel.weights``."""
        return {f"kernel.{k}": getattr(self, k) for k in _ARRAYS}

    @classmethod
    def from_arrays(cls, families: tuple[FeatureFamily, ...], arrays: dict[str, np.ndarray],
                    info: dict, prefix: str = "") -> KernelFunction:
        mine = own_arrays(arrays, f"{prefix}kernel.", _ARRAYS)
        d = sum(len(f.columns()) for f in families)
        D = np.shape(mine["offset"])[0] if np.ndim(mine["offset"]) == 1 else -1
        shapes = {"mean": (d,), "scale": (d,), "projection": (d, D), "offset": (D,),
                  "weights": (D,)}
        got = {k: require_float_array(mine[k], f"array {prefix}kernel.{k}",
                                      shapes[k] if D >= 1 else (None,), bound=MAX_WEIGHT)
               for k in _ARRAYS}
        if D < 1:
            raise FootfallError(f"array {prefix}kernel.offset must hold at least one feature")
        if not (got["scale"] > 0).all():
            raise FootfallError(f"array {prefix}kernel.scale must be > 0 (a standard deviation)")
        return cls(tuple(families), got["mean"], got["scale"], got["projection"], got["offset"],
                   got["weights"], info)


@dataclass(frozen=True)
class KernelLearner(Learner):
    """The kernel ranker as a registered learner (``--learner kernel``)."""

    name: str = "kernel"
    description: str = ("pairwise logistic regression (L2) on random Fourier features of the "
                        "columns: a kernel ranker, non-linear")
    function_type: type = KernelFunction
    n_components: int = 300  # random Fourier features D
    gamma_scale: float = 1.0  # gamma times the number of columns

    def fit(self, X, y, groups, *, Cs=10, cv: int = 5, selection: str = "1se",
            units=None) -> KernelRanker:
        """:class:`KernelRanker`, fitted (its own C path: ``Cs`` counts its points)."""
        n = min(int(Cs), 6) if np.isscalar(Cs) else Cs
        return KernelRanker(self.n_components, self.gamma_scale, Cs=n, cv=cv,
                            selection=selection).fit(X, y, groups, units)

    def function(self, fitted: KernelRanker, families: tuple[FeatureFamily, ...],
                 n_demonstrations: int) -> KernelFunction:
        """Every column kept (a kernel weighs them all): the fitted arrays and the record."""
        info: dict = {}
        for f in families:
            info.update(f.info())
        info.update({"lambda": fitted.lambda_, "C": fitted.C_, "cv_error": fitted.cv_error_,
                     "path": [vars(p) for p in fitted.path_],
                     "n_demonstrations": n_demonstrations, "n_components": self.n_components,
                     "gamma_scale": self.gamma_scale})
        return KernelFunction(tuple(families), fitted.mean_, fitted.scale_, fitted.projection_,
                              fitted.offset_, fitted.coef_, info)


register_learner(KernelLearner())
