"""Feature families: the extension point through which foothold features plug in.

A family computes a block of named feature columns for a candidate set F: the
27 terrain features, the templates of a library (Eq. 4), the 26 pose
features, or one of your own. Everything downstream -- the reward, the
learner, the model file, the dense scorer -- finds a family's columns by its
name and its column names, never by position. To add a family, subclass
:class:`FeatureFamily` in one module and decorate it with
:func:`register_family` (the registry :data:`FAMILIES`); a feature set
(:data:`FEATURE_SETS`) is a named tuple of family names. The built-in families
register in their own modules, which :mod:`footfall.features` imports. The
shared suite ``tests/test_feature_families.py`` checks every registered family.
"""

from __future__ import annotations

import hashlib
import json
from abc import ABC, abstractmethod
from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any, ClassVar

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.registry import Registry
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.core.state import RobotState
from footfall.features.config import FeatureConfig
from footfall.features.patches import FootholdPatches, foothold_patches


@dataclass(frozen=True, eq=False)
class Candidates:
    """What a feature family may read about a candidate set F.

    The patches around the footholds are computed on first use and shared by
    every family that reads them.
    """

    hmap: HeightMap  # the terrain
    footholds: np.ndarray  # (n, 3) [m] candidate contact points x, y, terrain height
    yaw: Any  # [rad] body heading that orients the patches: a float or (n,)
    mirror: Any  # mirror the patches in y (right legs): a bool or (n,)
    config: FeatureConfig  # patch scales and resolution
    state: RobotState | None = None  # the robot's state; state families (pose) need it
    robot: RobotDescription = LITTLEDOG
    given_patches: FootholdPatches | None = None  # patches already extracted, if any

    @classmethod
    def of_state(cls, hmap: HeightMap, state: RobotState, footholds: np.ndarray,
                 config: FeatureConfig, robot: RobotDescription = LITTLEDOG) -> Candidates:
        """The swing leg's candidates in ``state``: heading and mirroring from the state."""
        f = np.asarray(footholds, dtype=np.float64).reshape(-1, 3)
        return cls(hmap, f, state.yaw, robot.leg(state.swing_leg).mirrored, config, state, robot)

    @property
    def n(self) -> int:
        """Number of candidates."""
        return int(np.shape(self.footholds)[0])

    @cached_property
    def patches(self) -> FootholdPatches:
        """Relative patches of every scale around the footholds (computed once)."""
        if self.given_patches is not None:
            return self.given_patches
        source = self.__dict__.get("_patch_source")  # a set this one was made from (with_state)
        if source is not None:
            return source.patches
        return foothold_patches(self.hmap, self.footholds, self.yaw, self.mirror, self.config)

    def columns(self, family: FeatureFamily) -> np.ndarray:
        """``family.compute(self)``, read-only; computed once per candidate set for a family with
        a :meth:`FeatureFamily.memo_key` (every reward that reads it shares the matrix), and a
        terrain family's once for every state of :meth:`with_state`."""
        key = family.memo_key()
        if key is None:
            return family.compute(self)
        # frozen: the memos are kept beside the cached patches; a state family's is this set's own
        memo = self.__dict__.setdefault("_state_columns" if family.needs_state else "_columns", {})
        if key not in memo:
            x = family.compute(self)
            x.setflags(write=False)
            memo[key] = x
        return memo[key]

    def with_state(self, state: RobotState) -> Candidates:
        """The same footholds seen from another state of the same heading and swing leg: its
        patches and its terrain families' columns are this set's -- one computation for the
        rollouts of a planner, made when either set first reads them (a scorer that reads
        none, the expert, makes none) --, its state families' (the pose features) its own."""
        mirror = self.robot.leg(state.swing_leg).mirrored
        if not (np.array_equal(state.yaw, self.yaw) and np.array_equal(mirror, self.mirror)):
            raise ValueError("with_state: another heading or a mirrored leg sees other patches")
        other = Candidates(self.hmap, self.footholds, self.yaw, self.mirror, self.config, state,
                           self.robot, self.given_patches)
        other.__dict__["_patch_source"] = self.__dict__.get("_patch_source", self)
        other.__dict__["_columns"] = self.__dict__.setdefault("_columns", {})
        return other


@dataclass(frozen=True)
class DenseTerms:
    """What the dense scorer needs of a family that is linear in the patch heights, on one scale.

    The family declares columns over the scale's patch samples (in its patch
    sample order); the scorer hands it their products with every lattice
    window's relative heights ``c`` (heights less the foothold's own, 0 where
    a sample has no data), and the window's sums:

    * ``zt = z_columns.T @ c`` (b, n), ``zz`` (n,) the sum of ``c^2`` [m^2],
      ``total`` (n,) the sum of ``c`` [m], over the samples with data;
    * complete windows: :attr:`add_full` adds the family's weighted reward to
      a running sum;
    * windows with no-data samples (holes, the map's border), also
      ``mt = m_columns.T @ m`` (e, nd) with ``m`` the data mask and the sample
      count: :attr:`masked` returns the family's weighted reward of them.
    """

    z_columns: np.ndarray  # (taps, b) columns applied to the relative heights of every window
    m_columns: np.ndarray  # (taps, e) columns applied to the data mask of a gappy window
    add_full: Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], None]
    # (zt (b, n) in the scorer's dtype, zz (n,), total (n,), r (n,) float64 to add to) -> None
    masked: Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]
    # (zt (b, nd), mt (e, nd), zz (nd,), count (nd,)) -> reward (nd,) float64; NaN: no fit


class FeatureFamily(ABC):
    """A block of named foothold features (the interface every family implements).

    Subclasses are frozen dataclasses holding their parameters (a template
    library, bandwidths; none for the terrain and pose features). Required:
    :attr:`name`, :meth:`columns`, :meth:`compute` and :meth:`create`.
    Optional, with defaults that suit a parameter-free family: the dense form
    (:meth:`dense`), file I/O of parameters (:meth:`params`,
    :meth:`from_params`), and the learning hooks (:meth:`fit`, :meth:`prepare`,
    :meth:`from_prepared`, :meth:`tune`, :meth:`select`, :meth:`info`).
    """

    name: ClassVar[str]  # registry key; prefixes the family's columns in a reward ("pose.progress")
    needs_state: ClassVar[bool] = False  # True: a function of the robot's state, not only the terrain
    fit_options: ClassVar[tuple[str, ...]] = ()  # the options :meth:`fit` takes, by keyword

    # ------------------------------------------------------------ required
    @classmethod
    @abstractmethod
    def create(cls, config: FeatureConfig, robot: RobotDescription = LITTLEDOG) -> FeatureFamily:
        """The family before learning (a learned family fills its parameters in :meth:`fit`)."""

    @abstractmethod
    def columns(self) -> tuple[str, ...]:
        """Column names, unique within the family, in column order."""

    @abstractmethod
    def compute(self, c: Candidates) -> np.ndarray:
        """The feature matrix (n, len(columns())) of the candidates."""

    # ------------------------------------------------------------ optional
    def memo_key(self) -> Hashable | None:
        """A key equal for two families exactly when they compute the same columns from the same
        candidates, for :meth:`Candidates.columns` to compute them once; None (the default): no
        sharing. A family without learned parameters (terrain, pose features) returns one."""
        return None

    def dense(self, scale: int, weights: np.ndarray, dtype: np.dtype) -> DenseTerms | None:
        """The family's dense form on scale ``scale`` with its reward weights (k,) folded in.

        None (the default): the family is not linear in the patch heights, and
        the dense scorer evaluates :meth:`compute` on every lattice point
        instead (exact, but slower).
        """
        return None

    def params(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Learned parameters as named arrays and JSON metadata (for model files)."""
        return {}, {}

    @classmethod
    def from_params(cls, config: FeatureConfig, robot: RobotDescription,
                    arrays: Mapping[str, np.ndarray], meta: Mapping[str, Any]) -> FeatureFamily:
        """Inverse of :meth:`params`, refusing parameters it does not know.

        Raises :class:`FootfallError` naming the array or ``params`` field that is
        missing, unexpected or malformed (the default: there must be none).
        """
        require_no_params(arrays, meta)
        return cls.create(config, robot)

    def digest(self) -> str:
        """Digest of the family's parameters: equal digests compute equal features."""
        arrays, meta = self.params()
        h = hashlib.sha256(json.dumps([self.name, meta], sort_keys=True).encode())
        for key in sorted(arrays):
            h.update(key.encode())
            h.update(np.ascontiguousarray(arrays[key], dtype=np.float64).tobytes())
        return h.hexdigest()

    def fit(self, maps: list[HeightMap], states: list[RobotState], candidates: list[np.ndarray],
            chosen: list[int], rng: np.random.Generator, *, robot: RobotDescription = LITTLEDOG,
            log: Callable[[str], None] = lambda s: None, **options: Any) -> FeatureFamily:
        """The family with parameters built from training demonstrations (default: itself).

        ``options`` are the family's own settings, those named in
        :attr:`fit_options` (e.g. the templates' ``library_size``); training
        refuses any other (:func:`check_family_options`) before it fits.
        """
        return self

    def prepare(self, c: Candidates) -> Any:
        """What training keeps of the candidates (default: the features themselves).

        A family with tunable parameters keeps what does not depend on them
        (templates keep squared patch distances, free of the bandwidth).
        """
        return self.compute(c)

    def from_prepared(self, prepared: Any) -> np.ndarray:
        """The feature matrix from :meth:`prepare`'s result (default: it is the matrix)."""
        return prepared

    def tune(self, error: Callable[[FeatureFamily], float],
             log: Callable[[str], None] = lambda s: None, *,
             order_only: bool = False) -> FeatureFamily:
        """The family with its hyperparameters chosen by ``error(variant)``, the cross-validation
        error of the whole model with ``variant`` in its place (by default nothing to tune).

        ``order_only``: the learner reads only the order of each column's values
        (:attr:`footfall.learning.learner.Learner.order_only`); a hyperparameter that
        re-maps a column by a strictly monotone function is then set to a fixed value
        instead of searched for.
        """
        return self

    def select(self, nonzero: np.ndarray) -> tuple[FeatureFamily, np.ndarray]:
        """Drop columns a sparse learner left at zero: the reduced family and the kept mask.

        ``nonzero`` (k,) bool marks the columns with a non-zero weight. By
        default every column is kept (zero weights cost nothing); a template
        library keeps only the templates that carry weight (paper §III-B).
        """
        return self, np.ones(len(self.columns()), dtype=bool)

    def info(self) -> dict[str, Any]:
        """JSON facts about the family for a model's record (e.g. library sizes)."""
        return {}


def require_no_params(arrays: Mapping[str, np.ndarray], meta: Any) -> None:
    """Refuse parameters given to a family that has none: no arrays and ``params`` empty."""
    if arrays:
        raise FootfallError(f"has unexpected array(s) {', '.join(sorted(arrays))}")
    if meta != {}:
        raise FootfallError(f"params must be empty ({{}}), got {str(meta)[:60]}")


def check_family_options(families: Sequence[FeatureFamily],
                         options: Mapping[str, Mapping[str, Any]]) -> None:
    """Refuse options for a family not among ``families``, or that its :meth:`fit` does not
    take (:attr:`FeatureFamily.fit_options`): a misspelt option would otherwise do nothing."""
    by_name = {f.name: f for f in families}
    for name, opts in options.items():
        if name not in by_name:
            raise FootfallError(f"options for feature family {name!r}, which is not in the "
                                f"feature set ({', '.join(by_name)})")
        unknown = sorted(set(opts) - set(by_name[name].fit_options))
        if unknown:
            takes = ", ".join(by_name[name].fit_options) or "none"
            raise FootfallError(f"feature family {name!r} has no option "
                                f"{', '.join(map(repr, unknown))}; its options: {takes}")


# ---------------------------------------------------------------- registries
FAMILIES: Registry[type[FeatureFamily]] = Registry("feature family")
"""Every registered feature family by name: the built-in ones (registered by their modules,
which :mod:`footfall.features` imports), then those of plugins and of your own code."""

FEATURE_SETS: Registry[tuple[str, ...]] = Registry("feature set")
"""Named feature sets: the families a ranking function is learned on, in column order."""


def register_family(cls: type[FeatureFamily]) -> type[FeatureFamily]:
    """Class decorator: make a feature family available by its ``name``."""
    name = getattr(cls, "name", None)
    if not isinstance(name, str) or not name or "." in name:
        raise ValueError(f"a feature family needs a name without dots, got {name!r}")
    return FAMILIES.register(name, cls)


def unregister_family(name: str) -> None:
    """Forget a family (for tests that register one of their own), and the sets that use it."""
    FAMILIES.unregister(name)
    for key, families_ in FEATURE_SETS.items():
        if name in families_ and key not in _BUILTIN_SETS:
            FEATURE_SETS.unregister(key)


def families() -> dict[str, type[FeatureFamily]]:
    """Every registered feature family by name, the built-in ones first."""
    return dict(FAMILIES.items())


def register_feature_set(name: str, families: tuple[str, ...]) -> None:
    """Name a feature set: the families it uses, in column order."""
    if not families or len(set(families)) != len(families):
        raise ValueError(f"feature set {name!r} needs distinct families, got {families!r}")
    try:
        FEATURE_SETS.register(name, tuple(families))
    except ValueError:  # the name is taken: by the same set, named again, nothing changes
        if FEATURE_SETS.get(name) != tuple(families):
            raise


def family_class(name: str) -> type[FeatureFamily]:
    """The registered family called ``name``."""
    return FAMILIES.get(name)


def feature_set_families(feature_set: str) -> tuple[str, ...]:
    """The families of a feature set: a registered name, or family names joined by ``+``.

    ``"both"`` is the paper's templates + terrain features + pose; ``"terrain+pose"`` spells
    a set out, so a newly registered family is usable without naming a set for it.
    """
    known = FAMILIES.names()
    if isinstance(feature_set, str) and feature_set in FEATURE_SETS:
        return FEATURE_SETS.get(feature_set)
    parts = tuple(str(feature_set).split("+"))
    if len(parts) > 1 and all(p in known for p in parts) and len(set(parts)) == len(parts):
        return parts
    raise FootfallError(f"unknown feature set {feature_set!r}; use one of "
                        f"{', '.join(FEATURE_SETS)}, or family names joined by '+' "
                        f"({', '.join(known)})")


# The paper's three feature sets (§V), each with the pose features.
_BUILTIN_SETS = {"terrain": ("terrain", "pose"), "templates": ("templates", "pose"),
                 "both": ("terrain", "templates", "pose")}
for _name, _families in _BUILTIN_SETS.items():
    register_feature_set(_name, _families)
PAPER_FEATURE_SETS = tuple(_BUILTIN_SETS)  # the sets the paper's tables compare: (a), (b), (c)
