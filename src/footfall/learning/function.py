"""A learned ranking function of one leg group: feature families and what a learner made of them.

A :class:`RankingFunction` holds the feature families it reads, with their
learned parameters (the kept templates and their RBF bandwidths), the
learner's own arrays and its training record. It turns into a
:class:`~footfall.features.scorer.FootholdScorer` for the planners
(:meth:`RankingFunction.scorer`) and into named arrays for the model file
(:meth:`RankingFunction.arrays`, :meth:`RankingFunction.from_arrays`): each
learner keeps its own arrays, and the file never pickles. The linear
function of the paper (Eq. 1), :class:`LinearFunction`, is the one the
linear learners make; a non-linear learner's function is a
:class:`ColumnFunction` (a value predicted from the families' columns side
by side), scored by :class:`ColumnScorer`.
"""

from __future__ import annotations

import hashlib
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.validate import require_float_array
from footfall.features.config import FeatureConfig
from footfall.features.dense import ScoreGrid, dense_validity
from footfall.features.family import Candidates, FeatureFamily
from footfall.features.reward import LinearReward
from footfall.features.scorer import FootholdScorer
from footfall.features.template_library import TemplateLibrary
from footfall.features.templates import TemplateFeatures

MAX_WEIGHT = 1e20
"""Largest |weight| [reward per unit of feature] and feature scale a model file may hold.

Learned weights are w / scale with the scale floored at 1e-12, so well below; the bound keeps
every product of a weight with a feature (and the dense scorer's float32 sums) finite."""


class RankingFunction(ABC):
    """A learned ranking function over the columns of feature families (one leg group).

    Subclasses are frozen dataclasses with the fields ``families`` (the
    feature families, with their learned parameters) and ``info`` (the
    training record: lambda, cross-validation error, the families' facts),
    and whatever arrays their learner keeps.
    """

    families: tuple[FeatureFamily, ...]
    info: dict

    # ------------------------------------------------------------ required
    @abstractmethod
    def scorer(self, config: FeatureConfig, name: str) -> FootholdScorer:
        """The function as a foothold scorer with feature settings ``config``, called ``name``."""

    @abstractmethod
    def arrays(self) -> dict[str, np.ndarray]:
        """The learner's own arrays by name (the model file prefixes them with the leg group)."""

    @classmethod
    @abstractmethod
    def from_arrays(cls, families: tuple[FeatureFamily, ...], arrays: dict[str, np.ndarray],
                    info: dict, prefix: str = "") -> RankingFunction:
        """The function from its families and the arrays :meth:`arrays` wrote, each under its
        name with ``prefix`` before it (the model file's leg group, ``"front."``); every array
        checked (shape, finite, bounded: raise :class:`FootfallError` naming it)."""

    # ------------------------------------------------------------ shared
    @property
    def names(self) -> tuple[str, ...]:
        """Full column names (``family.column``), in column order."""
        return tuple(f"{f.name}.{c}" for f in self.families for c in f.columns())

    def family(self, name: str) -> FeatureFamily | None:
        """The family called ``name``, or None."""
        return next((f for f in self.families if f.name == name), None)

    @property
    def library(self) -> TemplateLibrary | None:
        """The kept templates (those the learner kept), if the function has any."""
        templates = self.family(TemplateFeatures.name)
        return templates.library if isinstance(templates, TemplateFeatures) else None


def weight_arrays(arrays: dict[str, np.ndarray], key: str, n: int
                  ) -> tuple[np.ndarray, np.ndarray]:
    """The weights ``<key>coef`` and scales ``<key>scale`` (n,) of a family, checked."""
    for name in ("coef", "scale"):
        if key + name not in arrays:
            raise FootfallError(f"lacks array {key}{name}")
    coef = require_float_array(arrays[key + "coef"], f"array {key}coef", (n,), bound=MAX_WEIGHT)
    scale = require_float_array(arrays[key + "scale"], f"array {key}scale", (n,),
                                bound=MAX_WEIGHT)
    if not (scale > 0).all():
        raise FootfallError(f"array {key}scale must be > 0 (a standard deviation)")
    return coef, scale


@dataclass(frozen=True, eq=False)
class LinearFunction(RankingFunction):
    """A linear ranking function w^T x (paper Eq. 1): one weight per raw column of each family."""

    families: tuple[FeatureFamily, ...]  # the families, with their learned parameters
    coef: tuple[np.ndarray, ...]  # per family (k_f,) weights on its raw columns
    scale: tuple[np.ndarray, ...]  # per family (k_f,) std of each column over the training pairs
    info: dict = field(default_factory=dict)  # lambda, C, cv error, path, the families' facts

    def __post_init__(self) -> None:
        if not (len(self.families) == len(self.coef) == len(self.scale)):
            raise FootfallError("a ranking function needs weights and scales for every family")
        for f, c, s in zip(self.families, self.coef, self.scale):
            n = len(f.columns())
            if np.shape(c) != (n,) or np.shape(s) != (n,):
                raise FootfallError(f"{f.name} weights do not match its {n} columns")

    def weights(self, name: str) -> np.ndarray:
        """The raw-column weights (k_f,) of the family called ``name``; empty if it has none."""
        return next((c for f, c in zip(self.families, self.coef) if f.name == name), np.zeros(0))

    def scorer(self, config: FeatureConfig, name: str = "learned") -> LinearReward:
        """The function as a :class:`LinearReward` over the same families and weights."""
        return LinearReward(self.families, self.coef, config, name)

    def reward(self, config: FeatureConfig, name: str = "learned") -> LinearReward:
        """The same as :meth:`scorer` (a linear function's scorer is a reward w^T x)."""
        return self.scorer(config, name)

    def arrays(self) -> dict[str, np.ndarray]:
        """``<family>.coef`` and ``<family>.scale`` of every family."""
        out = {}
        for f, c, s in zip(self.families, self.coef, self.scale):
            out[f"{f.name}.coef"] = c
            out[f"{f.name}.scale"] = s
        return out

    @classmethod
    def from_arrays(cls, families: tuple[FeatureFamily, ...], arrays: dict[str, np.ndarray],
                    info: dict, prefix: str = "") -> LinearFunction:
        pairs = [weight_arrays(arrays, f"{prefix}{f.name}.", len(f.columns())) for f in families]
        extra = sorted(set(arrays) - {f"{prefix}{f.name}.{k}" for f in families
                                      for k in ("coef", "scale")})
        if extra:
            raise FootfallError(f"unexpected array(s) {', '.join(extra[:4])}")
        return cls(tuple(families), tuple(c for c, _ in pairs), tuple(s for _, s in pairs), info)


def own_arrays(arrays: dict[str, np.ndarray], prefix: str, names: tuple[str, ...]
               ) -> dict[str, np.ndarray]:
    """A function's arrays ``<prefix><name>`` by ``name``: every one present, no other."""
    wanted = {f"{prefix}{n}": n for n in names}
    extra = sorted(set(arrays) - set(wanted))
    if extra:
        raise FootfallError(f"unexpected array(s) {', '.join(extra[:4])}")
    missing = [key for key in wanted if key not in arrays]
    if missing:
        raise FootfallError(f"lacks array {missing[0]}")
    return {n: arrays[key] for key, n in wanted.items()}


VETO_PENALTY = 1.0e3  # [value] taken from a candidate a learned veto refuses: far more than a
# ranker's values spread over a candidate set (the teacher's own veto takes as much)


class ColumnFunction(RankingFunction):
    """A ranking function that predicts a value from the families' columns side by side (not
    w^T x): a kernel or boosted ranker. Subclasses implement :meth:`predict`."""

    @abstractmethod
    def predict(self, X: np.ndarray) -> np.ndarray:
        """Values (n,) of candidates with features X (n, d) (finite; higher: preferred)."""

    def without_veto(self) -> ColumnFunction:
        """The function without a learned veto of the candidates a teacher refuses (itself if it
        has none): what a planner's path bias is scaled to (:attr:`ColumnScorer.spread_basis`)."""
        return self

    def refused_in_sets(self, X: np.ndarray, which: np.ndarray) -> np.ndarray | None:
        """(n,) bool: the candidates (rows of X (n, d)) a relative veto refuses among the others
        of their candidate set (``which`` (n,): each row's set), or None for a function
        without one (a row's value is then its own)."""
        return None

    def scorer(self, config: FeatureConfig, name: str = "learned") -> ColumnScorer:
        """The function as a :class:`ColumnScorer`."""
        return ColumnScorer(self, config, name)

    @property
    def n_columns(self) -> int:
        """Number of columns d the function reads."""
        return sum(len(f.columns()) for f in self.families)


@dataclass(frozen=True, eq=False)
class ColumnScorer(FootholdScorer):
    """A :class:`ColumnFunction`'s values of candidates: every family's columns, then predict.

    The value is not separable into a terrain part and a state part: with a
    family that reads the robot's state (pose features) all of it is the
    state part, and the terrain part only marks footholds that are not valid
    (-inf); without one, all of it is the terrain part, and the dense form
    evaluates it at every lattice point (the generic
    :meth:`FootholdScorer.dense`). Either way a candidate set is scored in one
    call, vectorised over its candidates.
    """

    function: ColumnFunction
    config: FeatureConfig = field(default_factory=FeatureConfig)
    name: str = "learned"

    def family_names(self) -> tuple[str, ...]:
        """Every family of the function (a non-linear function reads all its columns)."""
        return tuple(f.name for f in self.function.families)

    @property
    def spread_basis(self) -> FootholdScorer:
        """The function without its veto, if it has one (a veto's penalty is not a spread)."""
        plain = self.function.without_veto()
        return self if plain is self.function else ColumnScorer(plain, self.config, self.name)

    @property
    def has_state_part(self) -> bool:
        """Whether a family reads the robot's state (then the whole value is the state part)."""
        return any(f.needs_state for f in self.function.families)

    def _predicted(self, c: Candidates) -> np.ndarray:
        """The function's value of every valid candidate, -inf for the others, (n,)."""
        return self._predicted_each([c])[0]

    def _predicted_each(self, sets: Sequence[Candidates]) -> np.ndarray:
        """:meth:`_predicted` of each candidate set (of one size n), (len(sets), n): the valid
        rows of them all valued in one call of the function (each row's value is its own)."""
        n = sets[0].n if sets else 0
        if any(c.n != n for c in sets):
            raise FootfallError("candidate sets valued together must have the same size")
        out = np.full((len(sets), n), -np.inf)
        valid = [np.flatnonzero(c.patches.valid) for c in sets]
        blocks = [np.hstack([c.columns(f) for f in self.function.families])[v]
                  for c, v in zip(sets, valid) if v.size]
        if blocks:
            X = np.vstack(blocks)
            which = np.repeat(np.arange(len(sets)), [v.size for v in valid])
            where = np.concatenate(valid)
            finite = np.isfinite(X).all(axis=1)
            out[which[finite], where[finite]] = self.function.predict(X[finite])
            refused = self.function.refused_in_sets(X[finite], which[finite])
            if refused is not None:  # relative to the others of the same set
                out[which[finite][refused], where[finite][refused]] -= VETO_PENALTY
        return out

    def dense(self, hmap: HeightMap, *, spacing: float = 0.005, yaw: float = 0.0,
              mirror: bool = False, dtype: type = np.float32, fast: bool = True) -> ScoreGrid:
        """The terrain part at every lattice point: with a state family, only where a foothold
        is valid (:func:`~footfall.features.dense.dense_validity`, counted without a patch),
        else the generic dense form of the function's value."""
        if self.has_state_part:
            return dense_validity(hmap, self.config, spacing=spacing, yaw=yaw, mirror=mirror)
        return super().dense(hmap, spacing=spacing, yaw=yaw, mirror=mirror, dtype=dtype,
                             fast=fast)

    def terrain_values(self, c: Candidates) -> np.ndarray:
        """The value (terrain families only), or 0 / -inf (valid or not) when it needs the state."""
        if self.has_state_part:
            return np.where(c.patches.valid, 0.0, -np.inf)
        return self._predicted(c)

    def state_values(self, c: Candidates) -> np.ndarray:
        """The whole value when a family reads the state (0 where the terrain part is -inf)."""
        return self.state_values_each([c])[0]

    def state_values_each(self, sets: Sequence[Candidates]) -> np.ndarray:
        """:meth:`state_values` of each set, their rows valued in one call of the function."""
        if not self.has_state_part:
            return np.zeros((len(sets), sets[0].n if sets else 0))
        v = self._predicted_each(sets)
        return np.where(np.isfinite(v), v, 0.0)

    @cached_property
    def _digest(self) -> str:
        """Digest of the function's families and arrays and the settings (hashed once: a kernel
        function's arrays run to megabytes)."""
        digest = hashlib.sha256(type(self.function).__qualname__.encode()
                                + repr(self.config.to_dict()).encode())
        for family in self.function.families:
            digest.update(family.name.encode() + family.digest().encode())
        for name, array in sorted(self.function.arrays().items()):
            digest.update(name.encode() + np.ascontiguousarray(array).tobytes())
        return digest.hexdigest()

    def key(self, state: bool) -> str:
        """Digest of the function's families and arrays, the settings and the part; with a state
        family the terrain part is only validity under the settings, and so is its key (every
        such function on a board shares one grid of it)."""
        if not state and self.has_state_part:
            return hashlib.sha256(f"validity:{self.config.to_dict()!r}".encode()).hexdigest()
        return hashlib.sha256(f"{self._digest}:{state}".encode()).hexdigest()


def check_function(function: Any) -> RankingFunction:
    """``function`` if it is a ranking function, else a clear error."""
    if not isinstance(function, RankingFunction):
        raise FootfallError(f"a learner must make a RankingFunction, got {type(function).__name__}")
    return function
