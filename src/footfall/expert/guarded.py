"""A reward guarded by the expert: the reward chooses, the expert vetoes its severe mistakes.

The hand-tuned reward walks at least as well as the synthetic expert choosing
every foothold (docs/learning/teacher.md), yet by the expert's measure it
picks a foothold on a slanted face, a pit's rim or a riser's edge on a few
per cent of its steps. :class:`GuardedScorer` keeps the reward's choice
everywhere else: among the candidates it scores together, every one the
expert values short of its best by more than ``threshold`` loses
``penalty + shortfall`` of reward, so the reward's best unvetoed candidate
wins (a vetoed one only where every other is vetoed too, which cannot
happen: the expert's own best is never vetoed). It is a
:class:`~footfall.features.scorer.FootholdScorer`, so the ordinary footstep
planner walks it with the reward's path bias and shortlists, and its body
path and terrain grids are the reward's.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.core.state import RobotState, stance_target
from footfall.expert.corrections import SEVERE_SHORTFALL
from footfall.expert.protocol import Expert, expert_settings, values_each
from footfall.features.config import FeatureConfig
from footfall.features.dense import ScoreGrid
from footfall.features.family import Candidates
from footfall.features.scorer import FootholdScorer
from footfall.features.spread import path_bias_weight

VETO_PENALTY = 1.0e3  # [reward units] taken from a vetoed candidate (plus its shortfall), far
# more than the hand-tuned reward's whole spread over a candidate set


def vetoed(values: np.ndarray, threshold: float) -> np.ndarray:
    """The expert's shortfall (n,) [value units] of each candidate from the best of ``values``
    (n,) where it exceeds ``threshold`` [value units], else 0; all 0 for no candidate."""
    v = np.asarray(values, dtype=np.float64)
    if v.size == 0:
        return np.zeros(0)
    short = np.max(v) - v
    return np.where(short > threshold, short, 0.0)


@dataclass(frozen=True, eq=False)
class GuardedScorer(FootholdScorer):
    """``reward``'s values, less ``penalty + shortfall`` where ``expert`` values a candidate
    short of its best among the same candidates by more than ``threshold``."""

    reward: FootholdScorer  # chooses (its terrain part, state part and path bias)
    expert: Expert  # vetoes: values (hmap, state, candidates (n, 3) [m]) -> (n,), higher better
    threshold: float = SEVERE_SHORTFALL  # [value units] shortfall from the expert's best vetoed
    penalty: float = VETO_PENALTY  # [reward units] taken from a vetoed candidate

    def __post_init__(self) -> None:
        if not isinstance(self.reward, FootholdScorer):
            raise FootfallError(f"a guarded scorer guards a FootholdScorer, "
                                f"got {type(self.reward).__name__}")
        for what, v in (("threshold", self.threshold), ("penalty", self.penalty)):
            if not np.isfinite(v) or v < 0:
                raise FootfallError(f"the veto's {what} must be finite and >= 0, got {v!r}")

    @property
    def name(self) -> str:  # type: ignore[override]
        return f"{self.reward.name}, expert veto {self.threshold:g}"

    @property
    def config(self) -> FeatureConfig:  # type: ignore[override]
        return self.reward.config

    @property
    def spread_basis(self) -> FootholdScorer:
        """The reward: its path bias is the guarded reward's (a veto is not a spread)."""
        return self.reward.spread_basis

    def family_names(self) -> tuple[str, ...]:
        return self.reward.family_names()

    def terrain_values(self, c: Candidates) -> np.ndarray:
        """The reward's terrain part (n,); -inf: not a foothold."""
        return self.reward.terrain_values(c)

    @property
    def has_state_part(self) -> bool:
        return True

    def state_values(self, c: Candidates) -> np.ndarray:
        """The reward's state part (n,) less the veto of the candidates the expert judges
        severely short of its best of ``c`` (needs ``c.state``)."""
        return self.state_values_each([c])[0]

    def state_values_each(self, sets: Sequence[Candidates]) -> np.ndarray:
        """:meth:`state_values` of the same footholds in each set's state, the reward's and
        the expert's values of them all at once (:func:`values_each`)."""
        if any(c.state is None for c in sets):
            raise FootfallError("the expert's veto needs a robot state; none was given")
        n = sets[0].n if sets else 0
        base = self.reward.state_values_each(sets) if self.reward.has_state_part and sets else \
            np.zeros((len(sets), n))
        if n == 0:
            return base
        expert = values_each(self.expert, sets[0].hmap, [c.state for c in sets],
                             sets[0].footholds)
        short = np.stack([vetoed(row, self.threshold) for row in expert])
        return base - np.where(short > 0, self.penalty + short, 0.0)

    def dense(self, hmap: HeightMap, *, spacing: float = 0.005, yaw: float = 0.0,
              mirror: bool = False, dtype: type = np.float32, fast: bool = True) -> ScoreGrid:
        """The reward's terrain part on the lattice (the veto needs a state)."""
        return self.reward.dense(hmap, spacing=spacing, yaw=yaw, mirror=mirror, dtype=dtype,
                                 fast=fast)

    def key(self, state: bool) -> str:
        """The reward's terrain key; for the state part, the reward's with the veto's settings."""
        if not state:
            return self.reward.key(state=False)
        text = json.dumps({"reward": self.reward.key(state=True), "threshold": self.threshold,
                           "penalty": self.penalty, "expert": expert_settings(self.expert)},
                          sort_keys=True)
        return hashlib.sha256(f"guarded:{text}".encode()).hexdigest()


@dataclass(frozen=True, eq=False)
class GuardedExpert:
    """The guarded reward as a teacher (:class:`~footfall.expert.protocol.Expert`): it
    demonstrates and corrects footholds as the footstep planner would pick them greedily with
    :class:`GuardedScorer`, in the expert's value units.

    A candidate's value is ``rate * (reward - path bias) - veto``: the reward with the
    planner's pull toward the gait-nominal foothold (``path_bias`` [reward/m] scaled to the
    reward's spread, ``lead`` [m] ahead of the default stance), converted at ``rate`` [value
    units per reward unit] -- the expert's path preference over the planner's, so that a
    centimetre off the gait-nominal foothold costs the same in both and the reproduction's
    correction margin keeps its meaning -- less ``rate * (penalty + shortfall)``
    where ``expert`` values the candidate short of its best by more than ``threshold``.
    Noiseless: :meth:`choose` is the best value (ties: the lower index).
    """

    reward: FootholdScorer  # the reward that chooses
    expert: Expert  # the expert that vetoes
    path_bias: float  # [hand-tuned reward/m] the planner's bias_weight
    lead: float  # [m] the gait-nominal foothold ahead of the default stance
    rate: float  # [value units per reward unit]
    threshold: float = SEVERE_SHORTFALL  # [value units]
    penalty: float = VETO_PENALTY  # [reward units]
    robot: RobotDescription = LITTLEDOG

    def __post_init__(self) -> None:
        for what, v in (("path bias", self.path_bias), ("lead", self.lead), ("rate", self.rate)):
            if not (isinstance(v, (int, float)) and np.isfinite(v) and v >= 0):
                raise FootfallError(f"the guarded teacher's {what} must be a finite number "
                                    f">= 0, got {v!r}")

    @cached_property
    def scorer(self) -> GuardedScorer:
        """The guarded reward the footstep planner walks."""
        return GuardedScorer(self.reward, self.expert, self.threshold, self.penalty)

    def values(self, hmap: HeightMap, state: RobotState, candidates: np.ndarray) -> np.ndarray:
        """The teacher's value (n,) [value units] of each candidate (n, 3) [m]; -inf: not a
        foothold."""
        f = np.asarray(candidates, dtype=np.float64).reshape(-1, 3)
        if f.shape[0] == 0:
            return np.zeros(0)
        scorer = self.scorer
        c = Candidates.of_state(hmap, state, f, scorer.config, self.robot)
        target = stance_target(state, self.robot, self.lead)
        bias = path_bias_weight(scorer, self.path_bias) * np.hypot(*(f[:, :2] - target).T)
        return self.rate * (scorer.values(c) - bias)

    def verdict(self, hmap: HeightMap, state: RobotState, candidates: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`values` (n,), the candidates the expert vetoes (n,) bool -- those it values
        short of its best by more than ``threshold`` -- and the expert's values (n,) [value
        units] the veto is relative to."""
        values = self.values(hmap, state, candidates)
        if values.shape[0] == 0:
            return values, np.zeros(0, dtype=bool), np.zeros(0)
        expert = np.asarray(self.expert.values(hmap, state, candidates), dtype=np.float64)
        return values, vetoed(expert, self.threshold) > 0, expert

    def choose(self, hmap: HeightMap, state: RobotState, candidates: np.ndarray,
               rng: np.random.Generator) -> int:
        """Index of the best candidate (``rng`` unused: the teacher is noiseless)."""
        v = self.values(hmap, state, candidates)
        if v.shape[0] == 0:
            raise FootfallError("the teacher cannot choose from an empty candidate set")
        return int(np.argmax(v))

    def to_dict(self) -> dict:
        """The teacher's settings (recorded with each demonstration it makes)."""
        return {"reward": self.reward.name, "reward_key": self.reward.key(state=True),
                "expert": expert_settings(self.expert), "path_bias": self.path_bias,
                "lead": self.lead, "rate": self.rate, "threshold": self.threshold,
                "penalty": self.penalty}
