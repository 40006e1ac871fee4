"""The foothold scorer: the one interface through which planners rank a candidate set F.

A scorer gives the values of a candidate set F for a state (the paper's reward
R(f), Eq. 1, generalised: higher is better) and, optionally, a dense form over a
lattice of footholds for the planners. Whether it is ``w^T x`` over feature
families (:class:`~footfall.features.reward.LinearReward`, the hand-tuned
reward and every linear learned function), a non-linear learned function, or
the synthetic expert's own judgement is its own business: the planners call
this contract, never a weight vector.

The contract splits a value into a *terrain part*, which reads only the
terrain around a foothold and may be scored once per board on a lattice
(:meth:`FootholdScorer.dense`), and a *state part*, which needs the robot's
state (pose features, the expert). ``values = terrain part + state part``;
a scorer whose value is not separable puts all of it in the state part (and
then its terrain part only marks footholds that are not valid, with -inf).
"""

from __future__ import annotations

import hashlib
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence

import numpy as np

from footfall.core.heightmap import HeightMap
from footfall.core.registry import Registry
from footfall.features.config import FeatureConfig
from footfall.features.dense import ScoreGrid, dense_values
from footfall.features.family import Candidates


class FootholdScorer(ABC):
    """Values of a candidate set F for a state; the interface every reward implements.

    Required: :attr:`name`, :attr:`config`, :meth:`family_names` and
    :meth:`terrain_values`. A scorer that reads the robot's state overrides
    :meth:`state_values` and :attr:`has_state_part`; :meth:`dense` has a
    generic form (the terrain part evaluated at every lattice point) that a
    scorer with a faster one overrides; :meth:`key` identifies equal parts
    (planners cache a board's grids by it).
    """

    name: str  # shown in run logs, reports and on the teaching page
    config: FeatureConfig  # the patch scales and resolution it reads (validity of a foothold)
    own_path_preference: bool = False  # True: it values closeness to the path itself (the
    # synthetic expert's stance term), so a planner walks it without its path bias

    # ------------------------------------------------------------ required
    @abstractmethod
    def family_names(self) -> tuple[str, ...]:
        """Names of the feature families it reads (() for one that reads the terrain itself)."""

    @abstractmethod
    def terrain_values(self, c: Candidates) -> np.ndarray:
        """The terrain part (n,) of the candidates' values; -inf where a foothold is not valid.

        Reads only the terrain (``c.state`` may be None).
        """

    # ------------------------------------------------------------ optional
    @property
    def spread_basis(self) -> FootholdScorer:
        """The scorer whose spread sets a planner's path bias for this one: itself, unless it
        is another's values with something no spread should count (a veto)."""
        return self

    @property
    def has_state_part(self) -> bool:
        """Whether the value has a part that needs the robot's state."""
        return False

    def state_values(self, c: Candidates) -> np.ndarray:
        """The state part (n,) of the candidates' values, for ``c.state``; 0 without one."""
        return np.zeros(c.n)

    def state_values_each(self, sets: Sequence[Candidates]) -> np.ndarray:
        """:meth:`state_values` of each of ``sets`` -- the same footholds seen from several
        states, e.g. a planner's rollouts (:meth:`Candidates.with_state`) --, (len(sets), n).
        A scorer that values them faster in one pass overrides it, with the same numbers."""
        if not sets:
            return np.zeros((0, 0))
        return np.stack([self.state_values(c) for c in sets])

    def values(self, c: Candidates) -> np.ndarray:
        """The candidates' values (n,): terrain part plus state part; -inf: not a foothold."""
        r = self.terrain_values(c)
        return r + self.state_values(c) if self.has_state_part else r

    def dense(self, hmap: HeightMap, *, spacing: float = 0.005, yaw: float = 0.0,
              mirror: bool = False, dtype: type = np.float32, fast: bool = True) -> ScoreGrid:
        """The terrain part at every lattice point of ``hmap`` (every ``spacing`` [m]).

        ``yaw`` [rad] is the body heading that orients the patches, ``mirror``
        scores for a right leg; ``dtype`` and ``fast`` are hints for scorers
        with a matrix form (see :func:`footfall.features.dense.score_grid`).
        The generic form evaluates :meth:`terrain_values` at every lattice
        point from interpolated patches, in blocks.
        """
        return dense_values(hmap, self.terrain_values, self.config, spacing=spacing, yaw=yaw,
                            mirror=mirror)

    def key(self, state: bool) -> str:
        """Digest of the terrain part (``state`` False) or of the state part: equal parts, equal
        keys. The default names the object itself (no two scorers share a key)."""
        return hashlib.sha256(f"{type(self).__qualname__}:{id(self)}:{state}".encode()).hexdigest()


RewardFor = Callable[[str], FootholdScorer]  # leg name -> the scorer its footholds are ranked by

SCORERS: Registry[Callable[[FeatureConfig | None], FootholdScorer]] = Registry("scorer")
"""Named scorers that need no training (the hand-tuned reward, ``"hand-tuned"``; a plugin's
own): name -> factory ``(config or None for the default feature settings) -> FootholdScorer``."""
